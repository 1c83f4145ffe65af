# _openbricks_native for the CMake ports (esp32): the C control cores of firmware/native/ compiled
# with their MicroPython bindings from this folder, the same cores the host extension is built from.
add_library(usermod_openbricks INTERFACE)

set(OB_NATIVE_DIR ${CMAKE_CURRENT_LIST_DIR}/../..)
file(GLOB OB_CORE_SOURCES ${OB_NATIVE_DIR}/*.c)
file(GLOB OB_BINDING_SOURCES ${CMAKE_CURRENT_LIST_DIR}/*.c)

target_sources(usermod_openbricks INTERFACE ${OB_CORE_SOURCES} ${OB_BINDING_SOURCES})
target_include_directories(usermod_openbricks INTERFACE ${CMAKE_CURRENT_LIST_DIR} ${OB_NATIVE_DIR})

target_link_libraries(usermod INTERFACE usermod_openbricks)
