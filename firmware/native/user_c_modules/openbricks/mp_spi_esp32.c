/*
 * The hub's SPI as a sensor core's link (spi.h), on ESP-IDF's spi_master driver.
 *
 * Only this file knows the peripheral. One bus and one device per sensor;
 * the driver drives CS. Transfers are polling transactions (no queue, no
 * interrupt, no allocation), short enough for the hard tick: a 13-byte
 * ICM-45686 burst at 8 MHz is 13 us on the wire.
 * It cannot be compiled without ESP-IDF; keep it this small.
 */
#if defined(ESP_PLATFORM)

#include <string.h>

#include "driver/spi_master.h"
#include "mp_bindings.h"
#include "py/mphal.h"

typedef struct {
    spi_host_device_t host;
    spi_device_handle_t device;
} link_t;

static link_t links[2]; /* the two general-purpose SPI hosts, SPI2 and SPI3 */

static bool esp_transfer(void *ctx, const uint8_t *tx, uint8_t *rx, size_t n) {
    spi_transaction_t t;
    memset(&t, 0, sizeof t);
    t.length = n * 8u;
    t.tx_buffer = tx;
    t.rx_buffer = rx;
    return spi_device_polling_transmit(((link_t *)ctx)->device, &t) == ESP_OK;
}

static void esp_delay_ms(void *ctx, uint32_t ms) {
    (void)ctx;
    mp_hal_delay_ms(ms);
}

void ob_mp_spi_esp32_open(int spi_id, int sck, int mosi, int miso, int cs, uint32_t hz, int mode, ob_spi_t *spi) {
    /* machine.SPI's numbering: 1 = SPI2_HOST, 2 = SPI3_HOST. */
    if (spi_id < 1 || spi_id > 2) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("spi_id=%d: the ESP32's SPI buses are 1 and 2"), spi_id);
    }
    link_t *link = &links[spi_id - 1];
    if (link->device != NULL) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("SPI bus %d already reads a sensor; give another spi_id="),
                          spi_id);
    }
    link->host = spi_id == 1 ? SPI2_HOST : SPI3_HOST;
    const spi_bus_config_t bus = {
        .mosi_io_num = mosi, .miso_io_num = miso, .sclk_io_num = sck, .quadwp_io_num = -1, .quadhd_io_num = -1,
        .max_transfer_sz = 64,
    };
    const spi_device_interface_config_t device = {
        .mode = (uint8_t)mode, .clock_speed_hz = (int)hz, .spics_io_num = cs, .queue_size = 1,
    };
    esp_err_t err = spi_bus_initialize(link->host, &bus, SPI_DMA_DISABLED);
    if (err == ESP_OK && spi_bus_add_device(link->host, &device, &link->device) != ESP_OK) {
        spi_bus_free(link->host);
        link->device = NULL;
        err = ESP_FAIL;
    }
    if (err != ESP_OK) {
        mp_raise_msg_varg(&mp_type_OSError, MP_ERROR_TEXT("SPI bus %d (SCK %d, MOSI %d, MISO %d, CS %d) could not be "
                                                          "set up; machine.SPI(%d) may hold it"),
                          spi_id, sck, mosi, miso, cs, spi_id);
    }
    *spi = (ob_spi_t){esp_transfer, esp_delay_ms, link};
}

void ob_mp_spi_esp32_close(const ob_spi_t *spi) {
    link_t *link = spi->ctx;
    if (link != NULL && link->device != NULL) {
        spi_bus_remove_device(link->device);
        spi_bus_free(link->host);
        link->device = NULL;
    }
}

#endif /* ESP_PLATFORM */
