/*
 * The hard tick's timer on the hub (hard_timer.h): ESP-IDF's esp_timer, whose
 * callbacks run on the esp_timer task, below the MicroPython scheduler.
 * It cannot be compiled without ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include "esp_timer.h"
#include "hard_timer.h"
#include "py/mphal.h"

static esp_timer_handle_t timer;

bool ob_hard_timer_start(ob_hard_timer_fn_t fn, void *ctx, uint32_t period_us) {
    if (timer != NULL) {
        return true;
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
