/* A BioTac host program written against Total Phase's public Cheetah API (our own code, not vendor code).
 * Like a program built with the vendor's loader, it loads "cheetah.so" at run time from its own folder
 * (then the working folder), checks ch_c_version, and calls the c_ch_* functions.
 *
 * usage: biotac_client [batches] [44|sp] [dump file]
 *   -> prints "serial <n> <serial>" per sensor and a summary line.  "sp" samples the BioTac SP's 54-slot frame
 *   (E1..E24: E20..E24 are commands 0xC8, 0xCB, 0xCD, 0xCE, 0xD0), as the vendor's SP headers do whatever sensor
 *   is attached; a 19-electrode sensor answers E20..E24 with error words (first byte 0xA5), which are counted as
 *   error_words, never as samples.  A dump file receives the first batch's words: "slot sensor command word" (hex).
 */
#define _DEFAULT_SOURCE
#include <dlfcn.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef uint8_t u08;
typedef uint16_t u16;
typedef uint32_t u32;
#define CLIENT_API 0x0350u
#define MIN_LIBRARY 0x0306u
#define SENSORS 3
#define FRAMES_PER_BATCH 5

static const u08 SELECT[SENSORS] = {0x01, 0x02, 0x04};
static const u08 FRAME_CMDS[44] = {0xA2, 0x80, 0xA4, 0x80, 0xA7, 0x80, 0xA8, 0x80, 0xAB, 0x80, 0xAD, 0x80, 0xAE, 0x80,
                                   0xB0, 0x80, 0xB3, 0x80, 0xB5, 0x80, 0xB6, 0x80, 0xB9, 0x80, 0xBA, 0x80, 0xBC, 0x80,
                                   0xBF, 0x80, 0xC1, 0x80, 0xC2, 0x80, 0xC4, 0x80, 0xC7, 0x80, 0x83, 0x80, 0x85, 0x80,
                                   0x86, 0x80};
static const u08 SP_FRAME_CMDS[54] = {0xA2, 0x80, 0xA4, 0x80, 0xA7, 0x80, 0xA8, 0x80, 0xAB, 0x80, 0xAD, 0x80, 0xAE, 0x80,
                                      0xB0, 0x80, 0xB3, 0x80, 0xB5, 0x80, 0xB6, 0x80, 0xB9, 0x80, 0xBA, 0x80, 0xBC, 0x80,
                                      0xBF, 0x80, 0xC1, 0x80, 0xC2, 0x80, 0xC4, 0x80, 0xC7, 0x80, 0xC8, 0x80, 0xCB, 0x80,
                                      0xCD, 0x80, 0xCE, 0x80, 0xD0, 0x80, 0x83, 0x80, 0x85, 0x80, 0x86, 0x80};

static struct {
    int (*find_devices)(int, u16 *);
    int (*open)(int);
    int (*close)(int);
    int (*target_power)(int, u08);
    u32 (*sleep_ms)(u32);
    int (*spi_bitrate)(int, int);
    int (*spi_configure)(int, int, int, int, u08);
    int (*queue_clear)(int);
    int (*queue_oe)(int, u08);
    int (*queue_ss)(int, u08);
    int (*queue_byte)(int, int, u08);
    int (*queue_delay_ns)(int, int);
    int (*batch_length)(int);
    int (*batch_shift)(int, int, u08 *);
    int (*async_submit)(int);
    int (*async_collect)(int, int, u08 *);
    const char *(*status_string)(int);
} ch;

static void *load(const char *argv0) {
    char exe[PATH_MAX], path[PATH_MAX + 16];
    if (realpath(argv0, exe)) {
        snprintf(path, sizeof path, "%s/cheetah.so", dirname(exe));
        void *h = dlopen(path, RTLD_NOW);
        if (h) return h;
    }
    return dlopen("./cheetah.so", RTLD_NOW);
}

#define BIND(field, name)                                                              \
    do {                                                                               \
        *(void **)(&ch.field) = dlsym(lib, "c_ch_" name);                              \
        if (!ch.field) { fprintf(stderr, "cheetah.so lacks c_ch_%s\n", name); return 3; } \
    } while (0)

static int odd(u08 b) { int n = 0; while (b) { n += b & 1; b >>= 1; } return n & 1; }

int main(int argc, char **argv) {
    int batches = 20;
    if (argc > 1) {  /* a whole number of batches, 1 or more: "-1" or "ten" is refused, not read as 0 or -1 */
        char *end;
        long n = strtol(argv[1], &end, 10);
        if (end == argv[1] || *end || n < 1 || n > 1000000) {
            fprintf(stderr, "batches: a whole number from 1 to 1000000, not %s\n", argv[1]);
            return 1;
        }
        batches = (int)n;
    }
    int sp = argc > 2 && strcmp(argv[2], "sp") == 0;
    if (argc > 2 && !sp && strcmp(argv[2], "44") != 0) { fprintf(stderr, "frame: 44 or sp, not %s\n", argv[2]); return 1; }
    const u08 *FRAME_CMDS_USED = sp ? SP_FRAME_CMDS : FRAME_CMDS;
    const int FRAME = sp ? 54 : 44;
    FILE *dump = argc > 3 ? fopen(argv[3], "w") : NULL;
    if (argc > 3 && !dump) { fprintf(stderr, "cannot write %s\n", argv[3]); return 1; }
    void *lib = load(argv[0]);
    if (!lib) { fprintf(stderr, "cannot load cheetah.so: %s\n", dlerror()); return 2; }
    u32 (*version)(void) = (u32(*)(void))dlsym(lib, "ch_c_version");
    if (!version) { fprintf(stderr, "cheetah.so has no ch_c_version\n"); return 3; }
    u32 v = version();
    if ((v & 0xFFFF) < MIN_LIBRARY || (v >> 16) > CLIENT_API) { fprintf(stderr, "incompatible library %08x\n", v); return 3; }
    BIND(find_devices, "find_devices"); BIND(open, "open"); BIND(close, "close"); BIND(target_power, "target_power");
    BIND(sleep_ms, "sleep_ms"); BIND(spi_bitrate, "spi_bitrate"); BIND(spi_configure, "spi_configure");
    BIND(queue_clear, "spi_queue_clear"); BIND(queue_oe, "spi_queue_oe"); BIND(queue_ss, "spi_queue_ss");
    BIND(queue_byte, "spi_queue_byte"); BIND(queue_delay_ns, "spi_queue_delay_ns");
    BIND(batch_length, "spi_batch_length"); BIND(batch_shift, "spi_batch_shift");
    BIND(async_submit, "spi_async_submit"); BIND(async_collect, "spi_async_collect");
    BIND(status_string, "status_string");

    u16 ports[4];
    if (ch.find_devices(4, ports) < 1) { fprintf(stderr, "no Cheetah adapter found\n"); return 4; }
    int h = ch.open(ports[0] & 0x7FFF);
    if (h <= 0) { fprintf(stderr, "cannot open the adapter (%d)\n", h); return 4; }
    ch.spi_configure(h, 0, 0, 0, 0);
    ch.target_power(h, 1);
    ch.sleep_ms(100);
    ch.spi_bitrate(h, 4400);
    ch.queue_clear(h);
    ch.queue_oe(h, 1);

    /* serial numbers: read command and property id, wait, then one byte per shift with the select held */
    int present[SENSORS] = {0};
    for (int s = 0; s < SENSORS; ++s) {
        u08 tmp[4], byte = 0;
        char serial[32] = {0};
        ch.queue_clear(h); ch.queue_ss(h, SELECT[s]); ch.queue_byte(h, 1, 0x61); ch.queue_byte(h, 1, 0x15);
        ch.queue_ss(h, 0); ch.queue_delay_ns(h, 50000); ch.batch_shift(h, 2, tmp);
        for (int n = 0; n < 30; ++n) {
            ch.queue_clear(h); ch.queue_ss(h, SELECT[s]); ch.queue_byte(h, 1, 0x00); ch.batch_shift(h, 1, &byte);
            if (byte == 0x00 || byte == 0xFF) break;
            serial[n] = (char)byte;
        }
        ch.queue_clear(h); ch.queue_ss(h, 0); ch.batch_shift(h, 0, &byte);
        present[s] = serial[0] == 'B' && serial[1] == 'T';
        printf("serial %d %s\n", s + 1, present[s] ? serial : "N/A");
    }

    /* streaming: broadcast each command to all, 50 us, read every sensor back to back, pad to 4.4 kHz */
    ch.queue_clear(h);
    for (int f = 0; f < FRAMES_PER_BATCH; ++f)
        for (int k = 0; k < FRAME; ++k) {
            ch.queue_ss(h, 0x07); ch.queue_byte(h, 1, FRAME_CMDS_USED[k]); ch.queue_byte(h, 1, 0x00); ch.queue_ss(h, 0);
            ch.queue_delay_ns(h, 50000);
            for (int s = 0; s < SENSORS; ++s) { ch.queue_ss(h, SELECT[s]); ch.queue_byte(h, 2, 0x00); }
            ch.queue_ss(h, 0);
            /* pad the sample to 1/4400 s: besides the delays, the adapter spends the bits, one byte slot (8 SCK
               periods) per select command (6 per sample) and ~750 ns per run of bytes (4 per sample), the budget
               SynTouch's host code uses for the Cheetah */
            ch.queue_delay_ns(h, 227273 - 50000 - ((2 + 2 * SENSORS) * 8 + 6 * 8) * 1000000 / 4400 - 4 * 750);
        }
    int len = ch.batch_length(h);
    u08 *data = malloc((size_t)len);
    for (int i = 0; i < 4; ++i) ch.async_submit(h);
    long samples = 0, parity_errors = 0, error_words = 0, pac_n = 0;
    double pac_sum = 0, pac_sq = 0;
    for (int b = 0; b < batches; ++b) {
        int got = ch.async_collect(h, len, data);
        ch.async_submit(h);
        if (got != len) {
            fprintf(stderr, "batch failed: %d (%s)\n", got, got < 0 ? ch.status_string(got) : "short batch");
            return 5;
        }
        int per_slot = 2 + 2 * SENSORS;
        for (int i = 0; i < FRAMES_PER_BATCH * FRAME; ++i)
            for (int s = 0; s < SENSORS; ++s) {
                if (!present[s]) continue;
                u08 b0 = data[i * per_slot + 2 + 2 * s], b1 = data[i * per_slot + 3 + 2 * s];
                if (dump && b == 0) fprintf(dump, "%d %d %02x %02x%02x\n", i, s + 1, FRAME_CMDS_USED[i % FRAME], b0, b1);
                if (b0 == 0xA5) { error_words++; continue; } /* the sensor's error word: not a sample */
                samples++;
                if (!odd(b0) || !odd(b1)) { parity_errors++; continue; }
                int value = (b0 >> 1) * 32 + (b1 >> 3);
                if (s == 0 && FRAME_CMDS_USED[i % FRAME] == 0x80) { pac_sum += value; pac_sq += (double)value * value; pac_n++; }
            }
    }
    double mean = pac_n ? pac_sum / pac_n : 0, sd = pac_n ? sqrt(pac_sq / pac_n - mean * mean) : 0;
    printf("frames %d samples %ld parity_errors %ld pac_mean %.2f pac_std %.3f error_words %ld\n",
           batches * FRAMES_PER_BATCH, samples, parity_errors, mean, sd, error_words);
    if (dump) fclose(dump);
    free(data);
    ch.close(h);
    return 0;
}
