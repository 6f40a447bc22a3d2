/* A Cheetah-compatible adapter library backed by emulated BioTac sensors.
 *
 * Exports ch_c_version() and c_ch_<name>() for each public Cheetah API function ch_<name>(), with the same C
 * signatures and the semantics of Total Phase's published API: device discovery, open/close, SPI
 * configuration and bit rate, target power, a per-handle queue of slave selects, bytes, delays and output
 * enable, synchronous batch shift, asynchronous submit/collect, sleep.  Instead of USB, each shift sends the
 * queue to the emulator's server (a Unix socket named by BIOTAC_CHEETAH_SOCKET, default
 * /tmp/biotac-cheetah.sock), which clocks it through the emulated sensors in virtual time and returns MISO.
 * Queued delays and ch_sleep_ms advance the emulator's time exactly; nothing sleeps in wall time.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

typedef uint8_t u08;
typedef uint16_t u16;
typedef uint32_t u32;

#define LIB_VERSION 0x0350u       /* v3.50 */
#define OLDEST_CLIENT_API 0x0300u /* oldest client header accepted */
#define CH_OK 0
#define CH_UNABLE_TO_OPEN (-8)
#define CH_INVALID_HANDLE (-10)
#define CH_COMMUNICATION_ERROR (-7)
#define CH_SPI_BATCH_EMPTY_QUEUE (-101)
#define CH_SPI_ASYNC_EMPTY (-103)
#define CH_SPI_ASYNC_MAX_REACHED (-105)
#define MAX_ASYNC 64

typedef struct {
    u16 software, firmware, hardware;
    u32 hw_revs_for_sw, fw_revs_for_sw, drv_revs_for_sw;
    u16 api_req_by_sw;
} CheetahVersion;
typedef struct {
    CheetahVersion version;
    int features;
} CheetahExt;

enum { OP_SS = 1, OP_BYTES = 2, OP_DELAY_NS = 3, OP_OE = 4 };
enum { REQ_SHIFT = 1, REQ_SLEEP = 2, REQ_HELLO = 3 };

typedef struct {
    u08 *data; /* serialized ops */
    size_t len, cap;
    size_t nbytes; /* bytes that will be shifted */
} Queue;

typedef struct {
    int open, fd;
    int bitrate_khz;
    u08 power;
    Queue queue;
    Queue async[MAX_ASYNC];
    int async_head, async_count;
} Device;

static Device dev; /* one emulated adapter, port 0, handle 1 */

static const char *socket_path(void) {
    const char *p = getenv("BIOTAC_CHEETAH_SOCKET");
    return p && *p ? p : "/tmp/biotac-cheetah.sock";
}

static int connect_server(void) {
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    strncpy(addr.sun_path, socket_path(), sizeof addr.sun_path - 1);
    if (connect(fd, (struct sockaddr *)&addr, sizeof addr) < 0) { close(fd); return -1; }
    return fd;
}

static int send_all(int fd, const void *buf, size_t n) {
    const u08 *p = buf;
    while (n) { ssize_t k = write(fd, p, n); if (k <= 0) return -1; p += k; n -= (size_t)k; }
    return 0;
}

static int recv_all(int fd, void *buf, size_t n) {
    u08 *p = buf;
    while (n) { ssize_t k = read(fd, p, n); if (k <= 0) return -1; p += k; n -= (size_t)k; }
    return 0;
}

/* request: u08 type, u32 length, payload; reply: u32 length, payload */
static int request(u08 type, const u08 *payload, u32 len, u08 *reply, u32 cap, u32 *got) {
    u08 head[5] = {type, (u08)len, (u08)(len >> 8), (u08)(len >> 16), (u08)(len >> 24)};
    if (send_all(dev.fd, head, 5) || (len && send_all(dev.fd, payload, len))) return CH_COMMUNICATION_ERROR;
    u08 rl[4];
    if (recv_all(dev.fd, rl, 4)) return CH_COMMUNICATION_ERROR;
    u32 n = (u32)rl[0] | (u32)rl[1] << 8 | (u32)rl[2] << 16 | (u32)rl[3] << 24;
    u08 *tmp = malloc(n ? n : 1);
    if (!tmp || (n && recv_all(dev.fd, tmp, n))) { free(tmp); return CH_COMMUNICATION_ERROR; }
    u32 k = n < cap ? n : cap;
    if (reply && k) memcpy(reply, tmp, k);
    if (got) *got = n;
    free(tmp);
    return CH_OK;
}

static int push(Queue *q, const void *src, size_t n) {
    if (q->len + n > q->cap) {
        size_t cap = q->cap ? q->cap * 2 : 256;
        while (cap < q->len + n) cap *= 2;
        u08 *d = realloc(q->data, cap);
        if (!d) return -1;
        q->data = d;
        q->cap = cap;
    }
    memcpy(q->data + q->len, src, n);
    q->len += n;
    return 0;
}

static int push_op(Queue *q, u08 kind, u32 value) {
    u08 rec[5] = {kind, (u08)value, (u08)(value >> 8), (u08)(value >> 16), (u08)(value >> 24)};
    return push(q, rec, 5);
}

static int valid(int handle) { return handle == 1 && dev.open; }

/* Run a serialized queue on the emulator: payload = bitrate kHz u32, then the op records. */
static int shift(const Queue *q, int num_bytes, u08 *data_in) {
    if (q->len == 0) return CH_SPI_BATCH_EMPTY_QUEUE;
    u08 *payload = malloc(4 + q->len);
    if (!payload) return CH_COMMUNICATION_ERROR;
    u32 rate = (u32)dev.bitrate_khz;
    memcpy(payload, (u08[4]){(u08)rate, (u08)(rate >> 8), (u08)(rate >> 16), (u08)(rate >> 24)}, 4);
    memcpy(payload + 4, q->data, q->len);
    u32 got = 0;
    int cap = num_bytes < 0 ? 0 : num_bytes;
    int st = request(REQ_SHIFT, payload, (u32)(4 + q->len), data_in, (u32)cap, &got);
    free(payload);
    if (st != CH_OK) return st;
    return (int)(got < (u32)cap ? got : (u32)cap);
}

/* ---- exported API: ch_c_version and c_ch_* ---------------------------------------------------- */
u32 ch_c_version(void) { return (OLDEST_CLIENT_API << 16) | LIB_VERSION; }

int c_ch_find_devices_ext(int num_devices, u16 *devices, int num_ids, u32 *unique_ids) {
    int fd = dev.open ? dev.fd : connect_server();
    if (fd < 0) return 0;
    if (!dev.open) close(fd);
    if (devices && num_devices > 0) devices[0] = dev.open ? (u16)0x8000 : 0; /* CH_PORT_NOT_FREE when in use */
    if (unique_ids && num_ids > 0) unique_ids[0] = 1365000042u;
    return 1;
}

int c_ch_find_devices(int num_devices, u16 *devices) { return c_ch_find_devices_ext(num_devices, devices, 0, 0); }

static void fill_version(CheetahVersion *v) {
    memset(v, 0, sizeof *v);
    v->software = LIB_VERSION;
    v->firmware = 0x0300;
    v->hardware = 0x0200;
    v->api_req_by_sw = OLDEST_CLIENT_API;
}

int c_ch_open_ext(int port_number, CheetahExt *ext) {
    if (ext) memset(ext, 0, sizeof *ext);
    if (port_number != 0 || dev.open) return CH_UNABLE_TO_OPEN;
    int fd = connect_server();
    if (fd < 0) return CH_UNABLE_TO_OPEN;
    memset(&dev, 0, sizeof dev);
    dev.fd = fd;
    dev.open = 1;
    dev.bitrate_khz = 1000;
    if (request(REQ_HELLO, 0, 0, 0, 0, 0) != CH_OK) { close(fd); dev.open = 0; return CH_UNABLE_TO_OPEN; }
    if (ext) { fill_version(&ext->version); ext->features = 1; }
    return 1;
}

int c_ch_open(int port_number) { return c_ch_open_ext(port_number, 0); }

int c_ch_close(int handle) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    close(dev.fd);
    free(dev.queue.data);
    for (int i = 0; i < MAX_ASYNC; ++i) free(dev.async[i].data);
    memset(&dev, 0, sizeof dev);
    return CH_OK;
}

int c_ch_port(int handle) { return valid(handle) ? 0 : CH_INVALID_HANDLE; }
u32 c_ch_unique_id(int handle) { return valid(handle) ? 1365000042u : 0; }

const char *c_ch_status_string(int status) {
    switch (status) {
    case 0: return "ok";
    case -7: return "communication error (is the emulator's Cheetah server running?)";
    case -8: return "unable to open device";
    case -10: return "invalid handle";
    case -101: return "batch: empty queue";
    case -103: return "async: nothing to collect";
    case -105: return "async: too many batches submitted";
    default: return 0;
    }
}

int c_ch_version(int handle, CheetahVersion *version) {
    if (!version) return CH_OK;
    fill_version(version);
    if (!valid(handle)) version->firmware = version->hardware = 0;
    return CH_OK;
}

u32 c_ch_sleep_ms(u32 milliseconds) {
    if (dev.open) {
        u08 p[4] = {(u08)milliseconds, (u08)(milliseconds >> 8), (u08)(milliseconds >> 16), (u08)(milliseconds >> 24)};
        request(REQ_SLEEP, p, 4, 0, 0, 0);
    }
    return milliseconds;
}

int c_ch_target_power(int handle, u08 power_flag) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (power_flag != 0x80) dev.power = power_flag & 1;
    return dev.power;
}

int c_ch_host_ifce_speed(int handle) { return valid(handle) ? 1 : CH_INVALID_HANDLE; }
int c_ch_dev_addr(int handle) { return valid(handle) ? 1 : CH_INVALID_HANDLE; }

int c_ch_spi_bitrate(int handle, int bitrate_khz) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (bitrate_khz > 0) dev.bitrate_khz = bitrate_khz < 100 ? 100 : (bitrate_khz > 40000 ? 40000 : bitrate_khz);
    return dev.bitrate_khz;
}

int c_ch_spi_configure(int handle, int polarity, int phase, int bitorder, u08 ss_polarity) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    /* the emulated sensors speak mode 0, MSB first, active-low selects: other settings are accepted and
       would, on real hardware, garble the traffic; the emulator does not model that */
    (void)polarity; (void)phase; (void)bitorder; (void)ss_polarity;
    return CH_OK;
}

int c_ch_spi_queue_clear(int handle) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    dev.queue.len = dev.queue.nbytes = 0;
    return CH_OK;
}

int c_ch_spi_queue_oe(int handle, u08 oe) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    return push_op(&dev.queue, OP_OE, oe) ? CH_COMMUNICATION_ERROR : CH_OK;
}

int c_ch_spi_queue_delay_ns(int handle, int nanoseconds) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (nanoseconds <= 0) return 0;
    push_op(&dev.queue, OP_DELAY_NS, (u32)nanoseconds);
    return nanoseconds;
}

int c_ch_spi_queue_delay_cycles(int handle, int cycles) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (cycles <= 0) return 0;
    push_op(&dev.queue, OP_DELAY_NS, (u32)((long long)cycles * 1000000LL / dev.bitrate_khz));
    return cycles;
}

int c_ch_spi_queue_ss(int handle, u08 active) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    return push_op(&dev.queue, OP_SS, active & 7) ? CH_COMMUNICATION_ERROR : CH_OK;
}

int c_ch_spi_queue_array(int handle, int num_bytes, const u08 *data_out) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (num_bytes <= 0) return 0;
    if (push_op(&dev.queue, OP_BYTES, (u32)num_bytes) || push(&dev.queue, data_out, (size_t)num_bytes))
        return CH_COMMUNICATION_ERROR;
    dev.queue.nbytes += (size_t)num_bytes;
    return num_bytes;
}

int c_ch_spi_queue_byte(int handle, int count, u08 data) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (count <= 0) return 0;
    u08 *tmp = malloc((size_t)count);
    if (!tmp) return CH_COMMUNICATION_ERROR;
    memset(tmp, data, (size_t)count);
    int r = c_ch_spi_queue_array(handle, count, tmp);
    free(tmp);
    return r;
}

int c_ch_spi_batch_length(int handle) { return valid(handle) ? (int)dev.queue.nbytes : CH_INVALID_HANDLE; }

int c_ch_spi_batch_shift(int handle, int num_bytes, u08 *data_in) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    return shift(&dev.queue, num_bytes, data_in);
}

int c_ch_spi_async_submit(int handle) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (dev.async_count >= MAX_ASYNC) return CH_SPI_ASYNC_MAX_REACHED;
    if (dev.queue.len == 0) return CH_SPI_BATCH_EMPTY_QUEUE;
    Queue *slot = &dev.async[(dev.async_head + dev.async_count) % MAX_ASYNC];
    slot->len = slot->nbytes = 0;
    if (push(slot, dev.queue.data, dev.queue.len)) return CH_COMMUNICATION_ERROR;
    slot->nbytes = dev.queue.nbytes;
    dev.async_count++;
    return CH_OK;
}

int c_ch_spi_async_collect(int handle, int num_bytes, u08 *data_in) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (dev.async_count == 0) return CH_SPI_ASYNC_EMPTY;
    Queue *slot = &dev.async[dev.async_head];
    dev.async_head = (dev.async_head + 1) % MAX_ASYNC;
    dev.async_count--;
    return shift(slot, num_bytes, data_in);
}
