/*
 * The servo's settings as users name them (Servo(kp=...), Servo.settings()):
 * one table of names, fields and allowed ranges, with the messages that
 * refuse a value. The bindings only turn their language's objects into
 * numbers and raise what these functions write, so the hub and the host
 * refuse the same values with the same words.
 */
#ifndef OB_SERVO_SETTINGS_H
#define OB_SERVO_SETTINGS_H

#include <stdbool.h>
#include <stddef.h>

#include "servo.h"

typedef struct {
    const char *name;  /* the keyword users write */
    size_t offset;     /* of its field in ob_servo_config_t */
    bool is_ms;        /* a uint32_t of milliseconds, given as an int; else a float */
    float min;         /* smallest allowed value ... */
    bool min_open;     /* ... itself excluded */
    float max;         /* largest allowed value */
} ob_servo_setting_t;

#define OB_SERVO_SETTINGS_COUNT 22

extern const ob_servo_setting_t ob_servo_settings[OB_SERVO_SETTINGS_COUNT];

/* Room for any message below, with a `where` of up to 40 characters. */
#define OB_SERVO_SETTING_MSG_SIZE 480

/* Why a setting was refused: the exception a binding raises for it. */
typedef enum {
    OB_SETTING_OK = 0,
    OB_SETTING_TYPE_ERROR,  /* an unknown name, or not an int where milliseconds are asked for */
    OB_SETTING_VALUE_ERROR, /* out of range */
} ob_setting_status_t;

/* The row named name, or NULL with msg "<where>: unknown setting 'x'; the settings are: ...". */
const ob_servo_setting_t *ob_servo_setting_find(const char *name, const char *where, char *msg, size_t msg_size);

/*
 * Check value against the row and store it in cfg. is_int says the caller
 * was given an integer (milliseconds settings take nothing else; type_name
 * names what was given instead). On refusal cfg is unchanged and msg says
 * what, where and what is allowed.
 */
ob_setting_status_t ob_servo_setting_set(ob_servo_config_t *cfg, const ob_servo_setting_t *setting, double value,
                                         bool is_int, const char *type_name, const char *where, char *msg,
                                         size_t msg_size);

/* The setting's current value in cfg (milliseconds as a whole number). */
double ob_servo_setting_get(const ob_servo_config_t *cfg, const ob_servo_setting_t *setting);

/* A duty cap given by a user as argument `name` (Servo(duty_limit=...), set_duty_limit(limit_pct)):
 * within (0, 100] percent, else msg says so, followed by note (may be ""). */
bool ob_servo_duty_limit_valid(float limit_pct, const char *where, const char *name, const char *note, char *msg,
                               size_t msg_size);

/* The mode as Servo.state() names it: coast, brake, dc, speed, position. */
const char *ob_servo_mode_name(ob_servo_mode_t mode);

#endif /* OB_SERVO_SETTINGS_H */
