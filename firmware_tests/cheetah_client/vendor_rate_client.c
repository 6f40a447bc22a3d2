/* A test client that paces its samples the way SynTouch's published Cheetah host code (the "BioTac C Library for
 * Cheetah", biotac.c, bt_cheetah_configure_batch) does — our own code, written from that code's description.
 *
 * That library queues, for every sample of the 44-slot frame and a 3-sensor board:
 *     select all, command byte, 0x00, select none, delay 50 us,
 *     then per sensor: select it, two 0x00 bytes; select none, delay 10 us, delay `additional`,
 * and computes the padding `additional` (ns) so that a sample lasts 1/sample_rate:
 *     additional = 1e9 / rate_Hz
 *                  - (words * 16 + selects * 8) / clock_kHz * 1e6      words = sensors + 1, selects = sensors + 3
 *                  - 50000 - 10000 - 3000
 * i.e. it budgets 8 SCK periods for every select command and 3 us per sample for the adapter's own overheads.
 * It submits 16 asynchronous batches of 5 frames (50 ms) and then collects one and submits one, in a loop.
 *
 * usage: vendor_rate_client [batches]   -> prints "additional_ns <n>" and "samples <n> parity_errors <n>"
 */
#define _DEFAULT_SOURCE
#include <dlfcn.h>
#include <libgen.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

typedef uint8_t u08;
typedef uint16_t u16;
typedef uint32_t u32;
#define SENSORS 3
#define CLOCK_KHZ 4400
#define RATE_HZ 4400
#define AFTER_SAMPLE_NS 50000
#define INTERWORD_NS 10000
#define BATCH_MS 50
#define IN_FLIGHT 16

static const u08 SELECT[SENSORS] = {0x01, 0x02, 0x04};
static const u08 FRAME[44] = {0xA2, 0x80, 0xA4, 0x80, 0xA7, 0x80, 0xA8, 0x80, 0xAB, 0x80, 0xAD, 0x80, 0xAE, 0x80, 0xB0,
                              0x80, 0xB3, 0x80, 0xB5, 0x80, 0xB6, 0x80, 0xB9, 0x80, 0xBA, 0x80, 0xBC, 0x80, 0xBF, 0x80,
                              0xC1, 0x80, 0xC2, 0x80, 0xC4, 0x80, 0xC7, 0x80, 0x83, 0x80, 0x85, 0x80, 0x86, 0x80};

static int odd(u08 b) { int n = 0; while (b) { n += b & 1; b >>= 1; } return n & 1; }

int main(int argc, char **argv) {
    int batches = argc > 1 ? atoi(argv[1]) : 40;
    char exe[PATH_MAX], path[PATH_MAX + 16];
    void *lib = NULL;
    if (realpath(argv[0], exe)) {
        snprintf(path, sizeof path, "%s/cheetah.so", dirname(exe));
        lib = dlopen(path, RTLD_NOW);
    }
    if (!lib) { fprintf(stderr, "cannot load cheetah.so\n"); return 2; }
    int (*find_devices_ext)(int, u16 *, int, u32 *);
    int (*ch_open)(int), (*ch_close)(int), (*configure)(int, int, int, int, u08), (*power)(int, u08);
    u32 (*sleep_ms)(u32);
    int (*bitrate)(int, int), (*clear)(int), (*oe)(int, u08), (*ss)(int, u08), (*byte)(int, int, u08);
    int (*delay_ns)(int, int), (*length)(int), (*submit)(int), (*collect)(int, int, u08 *);
    const char *(*status_string)(int);
#define BIND(var, name)                                                                  \
    do {                                                                                 \
        *(void **)(&var) = dlsym(lib, "c_ch_" name);                                     \
        if (!var) { fprintf(stderr, "cheetah.so lacks c_ch_%s\n", name); return 3; }     \
    } while (0)
    BIND(find_devices_ext, "find_devices_ext"); BIND(ch_open, "open"); BIND(ch_close, "close");
    BIND(configure, "spi_configure"); BIND(power, "target_power"); BIND(sleep_ms, "sleep_ms");
    BIND(bitrate, "spi_bitrate"); BIND(clear, "spi_queue_clear"); BIND(oe, "spi_queue_oe");
    BIND(ss, "spi_queue_ss"); BIND(byte, "spi_queue_byte"); BIND(delay_ns, "spi_queue_delay_ns");
    BIND(length, "spi_batch_length"); BIND(submit, "spi_async_submit"); BIND(collect, "spi_async_collect");
    BIND(status_string, "status_string");

    u16 port;
    u32 id;
    if (find_devices_ext(1, &port, 1, &id) < 1) { fprintf(stderr, "no Cheetah adapter found\n"); return 4; }
    int h = ch_open(port & 0x7FFF);
    if (h <= 0) { fprintf(stderr, "cannot open the adapter (%d)\n", h); return 4; }
    configure(h, 0, 0, 0, 0);
    power(h, 1);
    sleep_ms(100);
    bitrate(h, CLOCK_KHZ);
    clear(h);
    oe(h, 1);

    /* the vendor's padding formula, as published */
    int words = SENSORS + 1, selects = SENSORS + 3;
    double additional = 1e9 / RATE_HZ - ((words * 16 + selects * 8) / (double)CLOCK_KHZ) * 1e6
                        - AFTER_SAMPLE_NS - INTERWORD_NS - 3000;
    int frames_per_batch = (int)(BATCH_MS / (1.0 / RATE_HZ * 44 * 1000));
    printf("additional_ns %d frames_per_batch %d\n", (int)additional, frames_per_batch);

    clear(h);
    for (int f = 0; f < frames_per_batch; ++f)
        for (int k = 0; k < 44; ++k) {
            ss(h, 0x07); byte(h, 1, FRAME[k]); byte(h, 1, 0x00); ss(h, 0x00);
            delay_ns(h, AFTER_SAMPLE_NS);
            for (int s = 0; s < SENSORS; ++s) { ss(h, SELECT[s]); byte(h, 2, 0x00); }
            ss(h, 0x00);
            delay_ns(h, INTERWORD_NS);
            delay_ns(h, (int)additional);
        }
    int len = length(h);
    u08 *data = malloc((size_t)len);
    long samples = 0, parity_errors = 0;
    for (int i = 0; i < IN_FLIGHT && i < batches; ++i) submit(h);
    for (int b = 0; b < batches; ++b) {
        int got = collect(h, len, data);
        if (got != len) {
            fprintf(stderr, "batch %d failed: %d (%s)\n", b, got, got < 0 ? status_string(got) : "short");
            return 5;
        }
        if (b + IN_FLIGHT < batches) submit(h);
        for (int i = 0; i < len / (2 + 2 * SENSORS); ++i)
            for (int s = 0; s < SENSORS; ++s) {
                u08 b0 = data[i * (2 + 2 * SENSORS) + 2 + 2 * s], b1 = data[i * (2 + 2 * SENSORS) + 3 + 2 * s];
                if (b0 == 0 && b1 == 0) continue; /* absent sensor */
                samples++;
                parity_errors += !odd(b0) || !odd(b1);
            }
    }
    printf("samples %ld parity_errors %ld\n", samples, parity_errors);
    free(data);
    oe(h, 0);
    ch_close(h);
    return 0;
}
