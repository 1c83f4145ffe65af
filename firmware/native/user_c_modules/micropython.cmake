# USER_C_MODULES entry for the CMake ports (esp32): pass this file's path, e.g.
#   make -C <micropython>/ports/esp32 USER_C_MODULES=<repo>/firmware/native/user_c_modules/micropython.cmake
include(${CMAKE_CURRENT_LIST_DIR}/openbricks/micropython.cmake)
