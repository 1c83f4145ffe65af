# _openbricks_bench: an in-memory SCS bus of emulated ST-3032s, emulated sensors and DC motors, for the unix port's tests only
# (firmware/unix_micropython.py builds it in; the hub's CMake build includes only ../openbricks).
SRC_USERMOD_C += $(USERMOD_DIR)/mod_bench_bus.c $(USERMOD_DIR)/mod_bench_sensors.c $(USERMOD_DIR)/mod_bench_dc.c
SRC_USERMOD_LIB_C += $(USERMOD_DIR)/emulated_servo.c $(USERMOD_DIR)/bench_servos.c $(USERMOD_DIR)/bench_sensors.c $(USERMOD_DIR)/bench_dc_motor.c
CFLAGS_USERMOD += -I$(USERMOD_DIR)
