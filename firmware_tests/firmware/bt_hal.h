/* Hardware-abstraction layer of the BioTac bridge firmware: everything the firmware needs from a board.
 * On the bench these are bound to the emulator in virtual time (firmware_tests/cosim.py). */
#ifndef BT_HAL_H
#define BT_HAL_H
#include <stddef.h>
#include <stdint.h>

/* One 16-bit SPI transfer of a queued sequence: it starts offset_ns after the sequence starts. */
typedef struct {
    uint32_t offset_ns;
    uint8_t cs;      /* 3-bit select code: 1, 2, 4, 5, 6 = sensors 1..5, 7 = all, 0 = none */
    uint8_t keep_cs; /* chip select stays asserted into the next transfer (the select code may change) */
    uint16_t mosi;
} bt_word;

typedef struct {
    void *ctx;
    /* Run a queued sequence of word transfers (like a DMA list); fills miso[i]; returns when the last ends. */
    void (*spi_sequence)(void *ctx, const bt_word *words, uint16_t *miso, size_t n);
    /* Clock n bytes with chip select cs asserted; keep_cs leaves it asserted afterwards. */
    void (*spi_bytes)(void *ctx, uint8_t cs, uint8_t keep_cs, const uint8_t *tx, uint8_t *rx, size_t n);
    void (*delay_us)(void *ctx, uint32_t us);
    uint64_t (*micros)(void *ctx);
    void (*uart_write)(void *ctx, const uint8_t *data, size_t n);
    size_t (*uart_read)(void *ctx, uint8_t *buf, size_t max); /* non-blocking: returns 0 when nothing waits */
} bt_hal;

#endif
