/*
 * The hub's H-bridge pins (hbridge_pins.h) on ESP-IDF: IN1/IN2 as GPIO
 * outputs, EN on an LEDC channel.
 *
 * Only this file knows the peripherals. Each bridge takes one low-speed
 * LEDC channel (the mode both the ESP32 and the ESP32-S3 have); bridges at
 * the same frequency share a timer, clocked from APB like MicroPython's own
 * machine.PWM (on the S3 every timer must use one clock source). The duty
 * resolution is the widest the frequency allows (16 bits at 1 kHz, 11 at
 * 20 kHz), and duty_max is 2^resolution, LEDC's "high all period".
 * machine.PWM hands out channels and timers from the bottom up and knows
 * nothing of these: they are taken from the top down, so the two only meet
 * when a program uses nearly every channel.
 *
 * `write` runs in the hard tick (the esp_timer task) and from the
 * interpreter, always under the motor lock, which is what makes LEDC's
 * non-thread-safe duty update safe here. It cannot be compiled without
 * ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include "driver/gpio.h"
#include "driver/ledc.h"
#include "esp_clk_tree.h"
#include "mp_bindings.h"

#define MODE LEDC_LOW_SPEED_MODE
#define CLOCK LEDC_USE_APB_CLK

typedef struct {
    bool used;
    int in1, in2, pwm;
    ledc_channel_t channel;
    ledc_timer_t timer;
} bridge_t;

typedef struct {
    uint32_t freq_hz; /* 0: free */
    uint32_t users;
    uint32_t duty_max;
} timer_slot_t;

static bridge_t bridges[LEDC_CHANNEL_MAX]; /* by channel */
static timer_slot_t timers[LEDC_TIMER_MAX];

static bool esp_write(void *ctx, bool in1, bool in2, uint32_t duty) {
    const bridge_t *bridge = ctx;
    bool ok = true;
    if (duty == 0u) { /* EN low first: the direction change below then switches nothing */
        ok = ledc_set_duty(MODE, bridge->channel, 0u) == ESP_OK && ledc_update_duty(MODE, bridge->channel) == ESP_OK;
    }
    /* Lows before highs: a reversal passes through coast (both low), never through brake. */
    if (!in1) {
        ok = gpio_set_level((gpio_num_t)bridge->in1, 0u) == ESP_OK && ok;
    }
    if (!in2) {
        ok = gpio_set_level((gpio_num_t)bridge->in2, 0u) == ESP_OK && ok;
    }
    if (in1) {
        ok = gpio_set_level((gpio_num_t)bridge->in1, 1u) == ESP_OK && ok;
    }
    if (in2) {
        ok = gpio_set_level((gpio_num_t)bridge->in2, 1u) == ESP_OK && ok;
    }
    if (duty != 0u) {
        ok = ledc_set_duty(MODE, bridge->channel, duty) == ESP_OK && ledc_update_duty(MODE, bridge->channel) == ESP_OK &&
             ok;
    }
    return ok;
}

/* A timer already running at freq_hz, else a free one (the highest first); -1 when none is left. */
static int pick_timer(uint32_t freq_hz) {
    for (int t = LEDC_TIMER_MAX - 1; t >= 0; t--) {
        if (timers[t].users > 0u && timers[t].freq_hz == freq_hz) {
            return t;
        }
    }
    for (int t = LEDC_TIMER_MAX - 1; t >= 0; t--) {
        if (timers[t].users == 0u) {
            return t;
        }
    }
    return -1;
}

static int pick_channel(void) {
    for (int c = LEDC_CHANNEL_MAX - 1; c >= 0; c--) {
        if (!bridges[c].used) {
            return c;
        }
    }
    return -1;
}

/* Start timer t at freq_hz unless it runs already; false when LEDC cannot make that frequency. */
static bool start_timer(int t, uint32_t freq_hz) {
    if (timers[t].users > 0u) {
        return true;
    }
    uint32_t src_hz = 0;
    if (esp_clk_tree_src_get_freq_hz((soc_module_clk_t)CLOCK, ESP_CLK_TREE_SRC_FREQ_PRECISION_CACHED, &src_hz) !=
        ESP_OK) {
        return false;
    }
    uint32_t bits = ledc_find_suitable_duty_resolution(src_hz, freq_hz);
    if (bits == 0u) {
        return false;
    }
    const ledc_timer_config_t config = {
        .speed_mode = MODE,
        .duty_resolution = (ledc_timer_bit_t)bits,
        .timer_num = (ledc_timer_t)t,
        .freq_hz = freq_hz,
        .clk_cfg = CLOCK,
        .deconfigure = false,
    };
    if (ledc_timer_config(&config) != ESP_OK) {
        return false;
    }
    timers[t].freq_hz = freq_hz;
    timers[t].duty_max = 1u << bits;
    return true;
}

static void release_timer(int t) {
    if (timers[t].users > 0u && --timers[t].users == 0u) {
        const ledc_timer_config_t config = {.speed_mode = MODE, .timer_num = (ledc_timer_t)t, .deconfigure = true};
        ledc_timer_pause(MODE, (ledc_timer_t)t);
        ledc_timer_config(&config);
        timers[t].freq_hz = 0u;
    }
}

void ob_mp_hbridge_esp32_open(int in1, int in2, int pwm, uint32_t freq_hz, ob_hbridge_pins_t *pins) {
    const int wires[3] = {in1, in2, pwm};
    for (int i = 0; i < 3; i++) {
        if (!GPIO_IS_VALID_OUTPUT_GPIO(wires[i])) {
            mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("HBridge: GPIO %d cannot drive an output"),
                              wires[i]);
        }
    }
    if (in1 == in2 || in1 == pwm || in2 == pwm) {
        mp_raise_msg_varg(&mp_type_ValueError,
                          MP_ERROR_TEXT("HBridge: in1, in2 and pwm must be three different GPIOs, not %d/%d/%d"), in1,
                          in2, pwm);
    }
    int channel = pick_channel();
    int timer = pick_timer(freq_hz);
    if (channel < 0 || timer < 0) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("HBridge: no free LEDC %s for the bridge on GPIO %d/%d/%d"),
                          channel < 0 ? "channel" : "timer", in1, in2, pwm);
    }
    if (!start_timer(timer, freq_hz)) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("HBridge: LEDC cannot run a PWM at %u Hz"),
                          (unsigned)freq_hz);
    }
    timers[timer].users++;
    const gpio_config_t direction = {
        .pin_bit_mask = (1ULL << in1) | (1ULL << in2),
        .mode = GPIO_MODE_OUTPUT,
        .pull_up_en = GPIO_PULLUP_DISABLE,
        .pull_down_en = GPIO_PULLDOWN_DISABLE,
        .intr_type = GPIO_INTR_DISABLE,
    };
    const ledc_channel_config_t enable = {
        .gpio_num = pwm,
        .speed_mode = MODE,
        .channel = (ledc_channel_t)channel,
        .intr_type = LEDC_INTR_DISABLE,
        .timer_sel = (ledc_timer_t)timer,
        .duty = 0u,
        .hpoint = 0,
        .sleep_mode = LEDC_SLEEP_MODE_NO_ALIVE_NO_PD,
    };
    /* Levels low before the pins turn outputs: the bridge must not twitch while it is set up. */
    bool ok = gpio_set_level((gpio_num_t)in1, 0u) == ESP_OK && gpio_set_level((gpio_num_t)in2, 0u) == ESP_OK &&
              gpio_config(&direction) == ESP_OK && ledc_channel_config(&enable) == ESP_OK;
    if (!ok) {
        release_timer(timer);
        mp_raise_msg_varg(&mp_type_OSError,
                          MP_ERROR_TEXT("HBridge: the GPIO/LEDC for the bridge on GPIO %d/%d/%d could not be set up"),
                          in1, in2, pwm);
    }
    bridge_t *bridge = &bridges[channel];
    *bridge = (bridge_t){true, in1, in2, pwm, (ledc_channel_t)channel, (ledc_timer_t)timer};
    *pins = (ob_hbridge_pins_t){esp_write, timers[timer].duty_max, bridge};
}

void ob_mp_hbridge_esp32_close(const ob_hbridge_pins_t *pins) {
    bridge_t *bridge = pins->ctx;
    if (bridge == NULL || !bridge->used) {
        return;
    }
    ledc_stop(MODE, bridge->channel, 0u);
    gpio_set_level((gpio_num_t)bridge->in1, 0u);
    gpio_set_level((gpio_num_t)bridge->in2, 0u);
    release_timer((int)bridge->timer);
    bridge->used = false;
}

#endif /* ESP_PLATFORM */
