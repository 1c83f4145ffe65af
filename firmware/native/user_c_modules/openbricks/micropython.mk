# _openbricks_native for the make ports (unix, ...): pass the parent folder,
#   make -C <micropython>/ports/unix USER_C_MODULES=<repo>/firmware/native/user_c_modules
# The bindings are scanned for qstrs; the cores include nothing of MicroPython, so they go in as
# plain library sources. The cores' folder is given as a real path: MicroPython names objects after
# the source's path relative to USER_C_MODULES, and a `../..` there would put them outside BUILD.
OB_NATIVE_DIR := $(realpath $(USERMOD_DIR)/../..)

SRC_USERMOD_C += $(wildcard $(USERMOD_DIR)/*.c)
SRC_USERMOD_LIB_C += $(wildcard $(OB_NATIVE_DIR)/*.c)
# The hard tick's timer: a POSIX thread on the unix port (the ESP32 build uses esp_timer instead).
SRC_USERMOD_LIB_C += $(OB_NATIVE_DIR)/platform/hard_timer_posix.c
CFLAGS_USERMOD += -I$(USERMOD_DIR) -I$(OB_NATIVE_DIR)
