/*
 * The _openbricks_native module: one globals table over the per-core bindings.
 */
#include "mp_bindings.h"

/* For the launcher's stop button: the same path a Ctrl-C takes, so the program
 * gets a KeyboardInterrupt at its next bytecode even when the request comes from
 * a timer callback (whose own exceptions never reach the program). */
static mp_obj_t mod_interrupt_main(void) {
    mp_sched_keyboard_interrupt();
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_0(mod_interrupt_main_obj, mod_interrupt_main);

#if !defined(ESP_PLATFORM)
/* Host builds tick motor_process themselves only while the hard tick runs it (every subscriber native);
 * otherwise their caller does (robotics.tick starts a machine.Timer). The hub always ticks itself. */
static mp_obj_t mod_ticks_itself(void) {
    return mp_obj_new_bool(ob_mp_motor_process_hard_ticked());
}
static MP_DEFINE_CONST_FUN_OBJ_0(mod_ticks_itself_obj, mod_ticks_itself);
#endif

/* motor_process lives on the heap (see mp_scheduler.c), so it is handed out here rather than from ROM. */
static mp_obj_t mod_getattr(mp_obj_t attr) {
    if (MP_OBJ_QSTR_VALUE(attr) == MP_QSTR_motor_process) {
        return ob_mp_motor_process_get();
    }
    return MP_OBJ_NULL;
}
static MP_DEFINE_CONST_FUN_OBJ_1(mod_getattr_obj, mod_getattr);

static const mp_rom_map_elem_t mod_globals_table[] = {
    {MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR__openbricks_native)},
    {MP_ROM_QSTR(MP_QSTR___getattr__), MP_ROM_PTR(&mod_getattr_obj)},
    {MP_ROM_QSTR(MP_QSTR_TrapezoidalProfile), MP_ROM_PTR(&ob_mp_profile_type)},
    {MP_ROM_QSTR(MP_QSTR_Observer), MP_ROM_PTR(&ob_mp_observer_type)},
    {MP_ROM_QSTR(MP_QSTR_Subscriber), MP_ROM_PTR(&ob_mp_subscriber_type)},
    {MP_ROM_QSTR(MP_QSTR_MotorIO), MP_ROM_PTR(&ob_mp_motor_io_type)},
    {MP_ROM_QSTR(MP_QSTR_MotorProcess), MP_ROM_PTR(&ob_mp_motor_process_type)},
    {MP_ROM_QSTR(MP_QSTR_Servo), MP_ROM_PTR(&ob_mp_servo_type)},
    {MP_ROM_QSTR(MP_QSTR_DriveBase), MP_ROM_PTR(&ob_mp_drivebase_type)},
    {MP_ROM_QSTR(MP_QSTR_ImuYaw), MP_ROM_PTR(&ob_mp_imu_yaw_type)},
    {MP_ROM_QSTR(MP_QSTR_PCNTEncoder), MP_ROM_PTR(&ob_mp_pcnt_encoder_type)},
    {MP_ROM_QSTR(MP_QSTR_ICM45686), MP_ROM_PTR(&ob_mp_icm45686_type)},
    {MP_ROM_QSTR(MP_QSTR_HBridge), MP_ROM_PTR(&ob_mp_hbridge_type)},
    {MP_ROM_QSTR(MP_QSTR_scs), MP_ROM_PTR(&ob_mp_scs_module)},
    {MP_ROM_QSTR(MP_QSTR_SerialBus), MP_ROM_PTR(&ob_mp_serial_bus_type)},
    {MP_ROM_QSTR(MP_QSTR_serial_bus), MP_ROM_PTR(&ob_mp_serial_bus_obj)},
    {MP_ROM_QSTR(MP_QSTR_interrupt_main), MP_ROM_PTR(&mod_interrupt_main_obj)},
    #if defined(ESP_PLATFORM)
    {MP_ROM_QSTR(MP_QSTR_ticks_itself), MP_ROM_TRUE},
    #else
    {MP_ROM_QSTR(MP_QSTR_ticks_itself), MP_ROM_PTR(&mod_ticks_itself_obj)},
    #endif
};
static MP_DEFINE_CONST_DICT(mod_globals, mod_globals_table);

const mp_obj_module_t ob_mp_module = {
    .base = {&mp_type_module},
    .globals = (mp_obj_dict_t *)&mod_globals,
};

MP_REGISTER_MODULE(MP_QSTR__openbricks_native, ob_mp_module);
