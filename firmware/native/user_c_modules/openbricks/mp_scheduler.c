/*
 * motor_process: the scheduler core behind a MicroPython object (host: py_scheduler.c).
 *
 * Servo and DriveBase are ticked through their C function pointer; any other
 * callable is called as callable(now_ms), the slow path kept for user code.
 * A subscriber's exception is held until every subscriber of the tick ran,
 * then the first one is raised.
 *
 * The module's motor_process is run by the hard tick (mp_hard_tick.c; the
 * esp_timer task on the hub, a thread on the unix port), which starts with
 * its first subscriber. When every subscriber is native and calls no Python
 * (a DriveBase or Servo on a bus engine's slots, the engine on a native UART)
 * the hard tick runs the round itself, under the motor lock, so a busy
 * interpreter never starves the controllers; tick() from Python then does
 * nothing, so nothing runs twice. Otherwise the hub queues the round into the
 * VM (mp_sched_schedule: only the VM thread may call Python), and other
 * builds are ticked by their caller. Either way each round reads the measured
 * mp_hal_ticks_ms(): a late or dropped tick costs control updates, never
 * trajectory time.
 *
 * Memory: the module's motor_process holds references to its subscribers, so
 * it lives on the GC heap behind a registered root pointer, not in static
 * memory the GC cannot see. It is allocated with a finaliser: a soft reset
 * sweeps the heap, and the finaliser stops the tick and forgets the object
 * before its subscribers are freed.
 */
#include "py/mphal.h"
#include "py/mpstate.h"

#include "mp_bindings.h"

#include "hard_timer.h"

#if defined(ESP_PLATFORM)
#define OB_HUB_TICK (1)
#else
#define OB_HUB_TICK (0)
#endif

/* ---- Subscriber. ---- */

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_subscriber_type,
    MP_QSTR_Subscriber,
    MP_TYPE_FLAG_NONE
    );

void ob_mp_subscriber_stash(ob_mp_subscriber_t *sub, mp_obj_t exc) {
    if (sub->error == MP_OBJ_NULL) {
        sub->error = exc;
    } else {
        mp_obj_print_exception(&mp_plat_print, exc); /* a second error in one call: report it, keep the first */
    }
}

void ob_mp_subscriber_raise(ob_mp_subscriber_t *sub) {
    mp_obj_t exc = sub->error;
    if (exc != MP_OBJ_NULL) {
        sub->error = MP_OBJ_NULL;
        nlr_raise(exc);
    }
}

/* ---- MotorProcess. ---- */

typedef struct _motor_process_obj_t motor_process_obj_t;

typedef struct {
    mp_obj_t obj;                 /* what was subscribed; MP_OBJ_NULL when the slot is free */
    ob_mp_subscriber_t *native;   /* its native part, or NULL for a Python callable */
    motor_process_obj_t *owner;
} slot_t;

struct _motor_process_obj_t {
    mp_obj_base_t base;
    ob_scheduler_t sched;
    slot_t slots[OB_SCHEDULER_MAX_SUBSCRIBERS];
    mp_obj_t error; /* first error of the running tick */
    bool is_module_process;
};

MP_REGISTER_ROOT_POINTER(mp_obj_t openbricks_motor_process);

static void collect_error(motor_process_obj_t *owner, mp_obj_t exc) {
    if (owner->error == MP_OBJ_NULL) {
        owner->error = exc;
    } else {
        mp_obj_print_exception(&mp_plat_print, exc);
    }
}

static void dispatch(void *ctx, uint32_t now_ms) {
    slot_t *slot = (slot_t *)ctx;
    if (slot->native != NULL) {
        slot->native->tick_fn(slot->native->tick_ctx, now_ms);
        mp_obj_t exc = slot->native->error;
        if (exc != MP_OBJ_NULL) {
            slot->native->error = MP_OBJ_NULL;
            collect_error(slot->owner, exc);
        }
        return;
    }
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_call_function_1(slot->obj, mp_obj_new_int_from_uint(now_ms));
        nlr_pop();
    } else {
        collect_error(slot->owner, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
}

static slot_t *find_slot(motor_process_obj_t *self, mp_obj_t obj) {
    for (size_t i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj == obj) {
            return &self->slots[i];
        }
    }
    return NULL;
}

static void release_slot(motor_process_obj_t *self, slot_t *slot) {
    ob_scheduler_unsubscribe(&self->sched, dispatch, slot);
    slot->obj = MP_OBJ_NULL;
    slot->native = NULL;
}

/* The native part of a Servo, DriveBase or SerialBus (or of a Python subclass of one), or NULL. */
static ob_mp_subscriber_t *as_subscriber(mp_obj_t obj) {
    static const mp_obj_type_t *const natives[] = {&ob_mp_servo_type, &ob_mp_drivebase_type, &ob_mp_serial_bus_type};
    for (size_t i = 0; i < MP_ARRAY_SIZE(natives); i++) {
        mp_obj_t base = mp_obj_cast_to_native_base(obj, MP_OBJ_FROM_PTR(natives[i]));
        if (base != MP_OBJ_NULL) {
            return MP_OBJ_TO_PTR(base);
        }
    }
    return NULL;
}

/* ---- The hard tick's work. ---- */

static void process_tick(motor_process_obj_t *self, uint32_t now_ms);

/* Every subscriber's tick is native and calls no Python: the timer's context may run the round. */
static bool all_hard_safe(const motor_process_obj_t *self) {
    if (self->sched.count == 0) {
        return false;
    }
    for (int i = 0; i < self->sched.count; i++) {
        const slot_t *slot = (const slot_t *)self->sched.subscribers[i].ctx;
        if (slot->native == NULL || !slot->native->hard_safe) {
            return false;
        }
    }
    return true;
}

bool ob_mp_motor_process_hard_ticked(void) {
    mp_obj_t process = MP_STATE_VM(openbricks_motor_process);
    return process != MP_OBJ_NULL && all_hard_safe(MP_OBJ_TO_PTR(process));
}

#if OB_HUB_TICK

static volatile bool hub_tick_queued;
static bool hub_tick_error_shown;

/* The VM's tick, for subscribers that call Python (encoder motors' IO callables, user callables). */
static mp_obj_t hub_tick_run(mp_obj_t unused) {
    (void)unused;
    hub_tick_queued = false;
    mp_obj_t process = MP_STATE_VM(openbricks_motor_process);
    if (process == MP_OBJ_NULL || ob_mp_motor_process_hard_ticked()) {
        return mp_const_none;
    }
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        process_tick(MP_OBJ_TO_PTR(process), (uint32_t)mp_hal_ticks_ms());
        nlr_pop();
        hub_tick_error_shown = false;
    } else if (!hub_tick_error_shown) {
        /* Once per run of failing ticks: a broken IO callable would otherwise print 1000 times a second. */
        hub_tick_error_shown = true;
        mp_printf(&mp_plat_print, "motor_process tick: ");
        mp_obj_print_exception(&mp_plat_print, MP_OBJ_FROM_PTR(nlr.ret_val));
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(hub_tick_run_obj, hub_tick_run);

/* From the hard tick: queue the VM's tick; never touch Python objects here. */
static void hub_tick_queue(void) {
    if (hub_tick_queued) {
        return; /* the previous tick has not run yet: this one is dropped, the clock stays measured */
    }
    hub_tick_queued = true;
    if (mp_sched_schedule(MP_OBJ_FROM_PTR(&hub_tick_run_obj), mp_const_none)) {
        mp_hal_wake_main_task();
    } else {
        hub_tick_queued = false;
    }
}

#else

static void hub_tick_queue(void) {
    /* This build's Python subscribers are ticked by its caller (robotics.tick, a simulator, a test). */
}

#endif

/*
 * Each hard period, in the timer's context, under the motor lock: when every
 * subscriber is native the control round runs right here, on the measured
 * millisecond clock, whatever the interpreter is doing; otherwise the hub
 * queues it for the VM as before.
 */
bool ob_mp_motor_process_hard_work(void *unused) {
    (void)unused;
    mp_obj_t process = MP_STATE_VM(openbricks_motor_process);
    if (process == MP_OBJ_NULL) {
        return false;
    }
    motor_process_obj_t *self = MP_OBJ_TO_PTR(process);
    if (!all_hard_safe(self)) {
        if (self->sched.count > 0) {
            hub_tick_queue();
        }
        return false;
    }
    /* Hard-safe subscribers never leave an exception: there is nothing to raise here. */
    ob_scheduler_tick(&self->sched, (uint32_t)mp_hal_ticks_ms());
    return true;
}

/* ---- Methods. ---- */

static void process_init(motor_process_obj_t *self) {
    ob_scheduler_init(&self->sched);
    for (size_t i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        self->slots[i].obj = MP_OBJ_NULL;
        self->slots[i].native = NULL;
        self->slots[i].owner = self;
    }
    self->error = MP_OBJ_NULL;
}

static mp_obj_t motor_process_make_new(const mp_obj_type_t *type, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    (void)args;
    if (n_args != 0 || n_kw != 0) {
        mp_raise_TypeError(MP_ERROR_TEXT("MotorProcess() takes no arguments"));
    }
    motor_process_obj_t *self = mp_obj_malloc(motor_process_obj_t, type);
    process_init(self);
    self->is_module_process = false;
    return MP_OBJ_FROM_PTR(self);
}

mp_obj_t ob_mp_motor_process_get(void) {
    if (MP_STATE_VM(openbricks_motor_process) == MP_OBJ_NULL) {
        motor_process_obj_t *self = mp_obj_malloc_with_finaliser(motor_process_obj_t, &ob_mp_motor_process_type);
        process_init(self);
        self->is_module_process = true;
        MP_STATE_VM(openbricks_motor_process) = MP_OBJ_FROM_PTR(self);
    }
    return MP_STATE_VM(openbricks_motor_process);
}

static mp_obj_t motor_process_subscribe(mp_obj_t self_in, mp_obj_t obj) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (find_slot(self, obj) != NULL) {
        return mp_const_none; /* idempotent */
    }
    ob_mp_subscriber_t *native = as_subscriber(obj);
    if (native != NULL) {
        if (native->tick_fn == NULL) {
            mp_raise_msg_varg(&mp_type_ValueError,
                              MP_ERROR_TEXT("motor_process.subscribe: this %s has no IO to tick (it was built "
                                            "without read/write callables); drive it with its update() method instead"),
                              mp_obj_get_type_str(obj));
        }
    } else if (!mp_obj_is_callable(obj)) {
        mp_raise_msg_varg(&mp_type_TypeError,
                          MP_ERROR_TEXT("motor_process.subscribe: expected a Servo, a DriveBase or a callable "
                                        "taking now_ms, not %s"),
                          mp_obj_get_type_str(obj));
    }
    slot_t *slot = find_slot(self, MP_OBJ_NULL);
    if (slot == NULL) {
        mp_raise_msg_varg(&mp_type_RuntimeError,
                          MP_ERROR_TEXT("motor_process.subscribe: all %d subscriber slots are taken; unsubscribe a "
                                        "motor or controller you no longer use"),
                          OB_SCHEDULER_MAX_SUBSCRIBERS);
    }
    slot->obj = obj;
    slot->native = native;
    if (!ob_scheduler_subscribe(&self->sched, dispatch, slot)) {
        slot->obj = MP_OBJ_NULL;
        slot->native = NULL;
        mp_raise_msg(&mp_type_RuntimeError, MP_ERROR_TEXT("motor_process.subscribe: the scheduler registry is full"));
    }
    if (self->is_module_process) {
        ob_mp_hard_tick_start();
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(motor_process_subscribe_obj, motor_process_subscribe);

static mp_obj_t motor_process_unsubscribe(mp_obj_t self_in, mp_obj_t obj) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    slot_t *slot = find_slot(self, obj);
    if (slot != NULL) {
        release_slot(self, slot);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(motor_process_unsubscribe_obj, motor_process_unsubscribe);

static mp_obj_t motor_process_is_subscribed(mp_obj_t self_in, mp_obj_t obj) {
    return mp_obj_new_bool(find_slot(MP_OBJ_TO_PTR(self_in), obj) != NULL);
}
static MP_DEFINE_CONST_FUN_OBJ_2(motor_process_is_subscribed_obj, motor_process_is_subscribed);

static void process_tick(motor_process_obj_t *self, uint32_t now_ms) {
    /* A subscriber may tick this process re-entrantly: keep the outer round's error aside. */
    mp_obj_t outer = self->error;
    self->error = MP_OBJ_NULL;
    ob_scheduler_tick(&self->sched, now_ms);
    mp_obj_t exc = self->error;
    self->error = outer;
    if (exc != MP_OBJ_NULL) {
        nlr_raise(exc);
    }
}

static mp_obj_t motor_process_tick(size_t n_args, const mp_obj_t *args) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(args[0]);
    if (self->is_module_process && ob_mp_motor_process_hard_ticked()) {
        return mp_const_none; /* the hard tick runs these subscribers: a second tick would run them twice */
    }
    /* tick() with no time reads the measured millisecond clock, as the hub's own tick does. */
    uint32_t now_ms = n_args > 1 && args[1] != mp_const_none ? ob_mp_time_ms(args[1], "motor_process.tick")
                                                              : (uint32_t)mp_hal_ticks_ms();
    process_tick(self, now_ms);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(motor_process_tick_obj, 1, 2, motor_process_tick);

static mp_obj_t motor_process_is_running(mp_obj_t self_in) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_bool(self->sched.count > 0);
}
static MP_DEFINE_CONST_FUN_OBJ_1(motor_process_is_running_obj, motor_process_is_running);

static mp_obj_t motor_process_now_ms(mp_obj_t self_in) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    return mp_obj_new_int_from_uint(self->sched.now_ms);
}
static MP_DEFINE_CONST_FUN_OBJ_1(motor_process_now_ms_obj, motor_process_now_ms);

static mp_obj_t motor_process_reset(mp_obj_t self_in) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    for (size_t i = 0; i < OB_SCHEDULER_MAX_SUBSCRIBERS; i++) {
        if (self->slots[i].obj != MP_OBJ_NULL) {
            release_slot(self, &self->slots[i]);
        }
    }
    ob_scheduler_init(&self->sched);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(motor_process_reset_obj, motor_process_reset);

static mp_obj_t motor_process_subscribers(mp_obj_t self_in) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    mp_obj_t list = mp_obj_new_list(0, NULL);
    for (int i = 0; i < self->sched.count; i++) { /* in tick order: the core registry's order */
        slot_t *slot = (slot_t *)self->sched.subscribers[i].ctx;
        mp_obj_list_append(list, slot->obj);
    }
    return list;
}
static MP_DEFINE_CONST_FUN_OBJ_1(motor_process_subscribers_obj, motor_process_subscribers);

/* Soft reset: the heap is swept and this object with it; stop the tick and forget it first. */
static mp_obj_t motor_process_del(mp_obj_t self_in) {
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (self->is_module_process) {
        ob_hard_timer_lock(); /* no hard tick may be inside a round of it */
        if (MP_STATE_VM(openbricks_motor_process) == self_in) {
            MP_STATE_VM(openbricks_motor_process) = MP_OBJ_NULL;
        }
        ob_hard_timer_unlock();
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(motor_process_del_obj, motor_process_del);

static const mp_obj_dict_t motor_process_locals;

static void motor_process_attr(mp_obj_t self_in, qstr attr, mp_obj_t *dest) {
    if (dest[0] != MP_OBJ_NULL) {
        return; /* read-only */
    }
    motor_process_obj_t *self = MP_OBJ_TO_PTR(self_in);
    switch (attr) {
        case MP_QSTR_tick_count:
            dest[0] = mp_obj_new_int_from_uint(self->sched.tick_count);
            break;
        case MP_QSTR_late_ticks:
            dest[0] = mp_obj_new_int_from_uint(self->sched.late_ticks);
            break;
        case MP_QSTR_last_dt_ms:
            dest[0] = mp_obj_new_int_from_uint(self->sched.last_dt_ms);
            break;
        case MP_QSTR_count:
            dest[0] = MP_OBJ_NEW_SMALL_INT(self->sched.count);
            break;
        case MP_QSTR_hard_tick_count:
        case MP_QSTR_hard_tick_selftest:
            dest[1] = MP_OBJ_SENTINEL; /* unlocked: the self-test waits for the hard tick to run */
            break;
        default:
            ob_mp_locked_attr(self_in, attr, dest, &motor_process_locals);
            break;
    }
}

static const mp_rom_map_elem_t motor_process_locals_table[] = {
    {MP_ROM_QSTR(MP_QSTR_subscribe), MP_ROM_PTR(&motor_process_subscribe_obj)},
    {MP_ROM_QSTR(MP_QSTR_unsubscribe), MP_ROM_PTR(&motor_process_unsubscribe_obj)},
    {MP_ROM_QSTR(MP_QSTR_is_subscribed), MP_ROM_PTR(&motor_process_is_subscribed_obj)},
    {MP_ROM_QSTR(MP_QSTR_tick), MP_ROM_PTR(&motor_process_tick_obj)},
    {MP_ROM_QSTR(MP_QSTR_is_running), MP_ROM_PTR(&motor_process_is_running_obj)},
    {MP_ROM_QSTR(MP_QSTR_now_ms), MP_ROM_PTR(&motor_process_now_ms_obj)},
    {MP_ROM_QSTR(MP_QSTR_reset), MP_ROM_PTR(&motor_process_reset_obj)},
    {MP_ROM_QSTR(MP_QSTR_subscribers), MP_ROM_PTR(&motor_process_subscribers_obj)},
    {MP_ROM_QSTR(MP_QSTR_hard_tick_count), MP_ROM_PTR(&ob_mp_hard_tick_count_obj)},
    {MP_ROM_QSTR(MP_QSTR_hard_tick_selftest), MP_ROM_PTR(&ob_mp_hard_tick_selftest_obj)},
    {MP_ROM_QSTR(MP_QSTR___del__), MP_ROM_PTR(&motor_process_del_obj)},
};
static MP_DEFINE_CONST_DICT(motor_process_locals, motor_process_locals_table);

MP_DEFINE_CONST_OBJ_TYPE(
    ob_mp_motor_process_type,
    MP_QSTR_MotorProcess,
    MP_TYPE_FLAG_NONE,
    make_new, motor_process_make_new,
    attr, motor_process_attr,
    locals_dict, &motor_process_locals
    );
