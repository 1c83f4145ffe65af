/*
 * The hub's PCNT units as the encoder core's counters (pcnt.h), on ESP-IDF's
 * pulse_cnt driver.
 *
 * Only this file knows the peripheral. One unit counts both edges of both
 * channels (x4 quadrature, the ESP-IDF rotary-encoder wiring: each channel's
 * edges count up or down by the other channel's level), between
 * -OB_PCNT_LIMIT and +OB_PCNT_LIMIT, where the hardware returns to 0; the
 * encoder core unwraps that from the hard tick's reads. The driver picks the
 * hardware unit; the manual's pcnt_unit is the runtime's bookkeeping.
 * It cannot be compiled without ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include "driver/pulse_cnt.h"
#include "mp_bindings.h"

/* APB clock the manual's filter cycles are counted in. */
#define APB_NS_PER_CYCLE_X10 125 /* 12.5 ns */

typedef struct {
    pcnt_unit_handle_t unit;
    pcnt_channel_handle_t channels[2];
} counter_t;

static counter_t counters[8]; /* the ESP32 has 8 units, the ESP32-S3 4 */

static bool esp_read(void *ctx, int32_t *raw) {
    int value;
    if (pcnt_unit_get_count(((counter_t *)ctx)->unit, &value) != ESP_OK) {
        return false;
    }
    *raw = value;
    return true;
}

static void release(counter_t *counter) {
    for (int i = 0; i < 2; i++) {
        if (counter->channels[i] != NULL) {
            pcnt_del_channel(counter->channels[i]);
            counter->channels[i] = NULL;
        }
    }
    if (counter->unit != NULL) {
        pcnt_unit_stop(counter->unit);
        pcnt_unit_disable(counter->unit);
        pcnt_del_unit(counter->unit);
        counter->unit = NULL;
    }
}

void ob_mp_pcnt_esp32_open(int pin_a, int pin_b, int filter_cycles, ob_pcnt_t *pcnt) {
    counter_t *counter = NULL;
    for (size_t i = 0; i < MP_ARRAY_SIZE(counters); i++) {
        if (counters[i].unit == NULL) {
            counter = &counters[i];
            break;
        }
    }
    const pcnt_unit_config_t unit_config = {.low_limit = -OB_PCNT_LIMIT, .high_limit = OB_PCNT_LIMIT};
    const pcnt_chan_config_t a_config = {.edge_gpio_num = pin_a, .level_gpio_num = pin_b};
    const pcnt_chan_config_t b_config = {.edge_gpio_num = pin_b, .level_gpio_num = pin_a};
    const pcnt_glitch_filter_config_t filter = {.max_glitch_ns = (uint32_t)filter_cycles * APB_NS_PER_CYCLE_X10 / 10u};
    if (counter == NULL || pcnt_new_unit(&unit_config, &counter->unit) != ESP_OK) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("PCNTEncoder: no free PCNT unit for GPIO %d/%d"), pin_a,
                          pin_b);
    }
    bool ok = (filter_cycles == 0 || pcnt_unit_set_glitch_filter(counter->unit, &filter) == ESP_OK) &&
              pcnt_new_channel(counter->unit, &a_config, &counter->channels[0]) == ESP_OK &&
              pcnt_new_channel(counter->unit, &b_config, &counter->channels[1]) == ESP_OK &&
              /* A leading B counts up: A's edges count by B's level, B's the other way round. */
              pcnt_channel_set_edge_action(counter->channels[0], PCNT_CHANNEL_EDGE_ACTION_DECREASE,
                                           PCNT_CHANNEL_EDGE_ACTION_INCREASE) == ESP_OK &&
              pcnt_channel_set_level_action(counter->channels[0], PCNT_CHANNEL_LEVEL_ACTION_KEEP,
                                            PCNT_CHANNEL_LEVEL_ACTION_INVERSE) == ESP_OK &&
              pcnt_channel_set_edge_action(counter->channels[1], PCNT_CHANNEL_EDGE_ACTION_INCREASE,
                                           PCNT_CHANNEL_EDGE_ACTION_DECREASE) == ESP_OK &&
              pcnt_channel_set_level_action(counter->channels[1], PCNT_CHANNEL_LEVEL_ACTION_KEEP,
                                            PCNT_CHANNEL_LEVEL_ACTION_INVERSE) == ESP_OK &&
              pcnt_unit_enable(counter->unit) == ESP_OK && pcnt_unit_clear_count(counter->unit) == ESP_OK &&
              pcnt_unit_start(counter->unit) == ESP_OK;
    if (!ok) {
        release(counter);
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("PCNTEncoder: the PCNT unit for GPIO %d/%d could not be "
                                                          "set up"),
                          pin_a, pin_b);
    }
    *pcnt = (ob_pcnt_t){esp_read, counter};
}

void ob_mp_pcnt_esp32_close(const ob_pcnt_t *pcnt) {
    if (pcnt->ctx != NULL) {
        release(pcnt->ctx);
    }
}

#endif /* ESP_PLATFORM */
