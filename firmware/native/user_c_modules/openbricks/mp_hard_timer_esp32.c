/*
 * The hard tick's timer on the hub (hard_timer.h): ESP-IDF's esp_timer, whose
 * callbacks run on the esp_timer task, below the MicroPython scheduler, and
 * the motor lock as a FreeRTOS recursive mutex (the timer only tries it).
 * It cannot be compiled without ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include "esp_timer.h"
#include "freertos/FreeRTOS.h"
#include "freertos/semphr.h"
#include "hard_timer.h"
#include "py/mphal.h"

static esp_timer_handle_t timer;
static SemaphoreHandle_t motor_lock; /* recursive mutex, created with the first start or lock */

static SemaphoreHandle_t lock_handle(void) {
    if (motor_lock == NULL) {
        motor_lock = xSemaphoreCreateRecursiveMutex();
    }
    return motor_lock;
}

void ob_hard_timer_lock(void) {
    xSemaphoreTakeRecursive(lock_handle(), portMAX_DELAY);
}

bool ob_hard_timer_try_lock(void) {
    return motor_lock != NULL && xSemaphoreTakeRecursive(motor_lock, 0) == pdTRUE;
}

void ob_hard_timer_unlock(void) {
    xSemaphoreGiveRecursive(motor_lock);
}

bool ob_hard_timer_start(ob_hard_timer_fn_t fn, void *ctx, uint32_t period_us) {
    if (timer != NULL) {
        return true;
    }
    if (lock_handle() == NULL) {
        return false;
    }
    const esp_timer_create_args_t args = {.callback = fn, .arg = ctx, .name = "ob_hard_tick"};
    if (esp_timer_create(&args, &timer) != ESP_OK) {
        return false;
    }
    return esp_timer_start_periodic(timer, period_us) == ESP_OK;
}

uint32_t ob_hard_timer_now_us(void) {
    return (uint32_t)esp_timer_get_time();
}

void ob_hard_timer_sleep_ms(uint32_t ms) {
    mp_hal_delay_ms(ms);
}

#endif /* ESP_PLATFORM */
