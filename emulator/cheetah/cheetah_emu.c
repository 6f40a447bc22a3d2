/* A Cheetah-compatible adapter library backed by emulated BioTac sensors.
 *
 * Exports ch_c_version() and c_ch_<name>() for each public Cheetah API function ch_<name>(), with the same C
 * signatures and the semantics of Total Phase's published API: device discovery, open/close, SPI
 * configuration and bit rate, target power, a per-handle queue of slave selects, bytes, delays and output
 * enable, synchronous batch shift, asynchronous submit/collect, sleep.  Instead of USB, the adapter is the
 * emulator's server (bench/hosts/cheetah_server.py) on a Unix socket named by BIOTAC_CHEETAH_SOCKET; it clocks
 * each queue through the emulated sensors in virtual time and returns MISO.  Queued delays and ch_sleep_ms
 * advance the emulator's time exactly; nothing sleeps in wall time while an adapter is open.
 *
 * Behaving like the device:
 *  - one client per adapter: ch_find_devices reports the port ORed with CH_PORT_NOT_FREE while another program
 *    has it open, and ch_open then fails with CH_UNABLE_TO_OPEN (as a second open of a real adapter does);
 *  - a server that goes away yields CH_COMMUNICATION_ERROR from every call that needs it, never a signal:
 *    sockets are written with MSG_NOSIGNAL; ch_sleep_ms, which returns the milliseconds slept, then returns 0;
 *  - the socket must live in a private folder (owned by this user, mode 0700) and be served by this user
 *    (checked with SO_PEERCRED); there is no default path, so nothing is ever found at a shared location;
 *  - ch_spi_async_submit hands the batch to the adapter at once (it starts then, in the adapter's time);
 *    ch_spi_async_collect waits for its result; a synchronous shift with batches pending is refused with
 *    CH_SPI_ASYNC_PENDING;
 *  - ch_spi_configure's polarity, phase, bit order and slave-select polarity reach the adapter, which clocks the
 *    bus accordingly: settings the sensors (mode 0, MSB first, active-low selects) do not use garble the
 *    traffic as they would on a real bus.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <libgen.h>
#include <limits.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

typedef uint8_t u08;
typedef uint16_t u16;
typedef uint32_t u32;

#define LIB_VERSION 0x0350u       /* v3.50 */
#define OLDEST_CLIENT_API 0x0300u /* oldest client header accepted */
#define CH_OK 0
#define CH_COMMUNICATION_ERROR (-7)
#define CH_UNABLE_TO_OPEN (-8)
#define CH_INVALID_HANDLE (-10)
#define CH_CONFIG_ERROR (-11)
#define CH_SPI_BATCH_EMPTY_QUEUE (-101)
#define CH_SPI_ASYNC_EMPTY (-103)
#define CH_SPI_ASYNC_PENDING (-104)
#define CH_SPI_ASYNC_MAX_REACHED (-105)
#define CH_PORT_NOT_FREE 0x8000
#define MAX_ASYNC 64
#define UNIQUE_ID 1365000042u

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
enum { REQ_SHIFT = 1, REQ_SLEEP = 2, REQ_HELLO = 3, REQ_QUERY = 4, REQ_SUBMIT = 5, REQ_COLLECT = 6 };

typedef struct {
    u08 *data; /* serialized ops */
    size_t len, cap;
    size_t nbytes; /* bytes that will be shifted */
} Queue;

typedef struct {
    int open, fd, broken;
    int bitrate_khz;
    u08 power;
    u08 mode;        /* polarity | phase << 1 | bitorder << 2 */
    u08 ss_polarity; /* bit i: SS line i active high */
    Queue queue;
    int async_count; /* submitted, not yet collected */
} Device;

static Device dev; /* one emulated adapter, port 0, handle 1 */

/* ---- the server's socket: private, this user's ------------------------------------------------------- */
static void complain(const char *path, const char *why) {
    static int said = 0;
    if (said++) return;
    if (path)
        fprintf(stderr, "cheetah.so (BioTac emulator): not using BIOTAC_CHEETAH_SOCKET=%s: %s\n", path, why);
    else
        fprintf(stderr, "cheetah.so (BioTac emulator): BIOTAC_CHEETAH_SOCKET %s\n", why);
}

static const char *socket_path(void) {
    const char *p = getenv("BIOTAC_CHEETAH_SOCKET");
    if (!p || !*p) { /* no default: never look at a shared location */
        complain(NULL, "is not set: start `biotac-bench cheetah serve` and export the line it prints");
        return NULL;
    }
    if (strlen(p) >= sizeof(((struct sockaddr_un *)0)->sun_path)) { complain(p, "path too long"); return NULL; }
    char copy[PATH_MAX];
    snprintf(copy, sizeof copy, "%s", p);
    struct stat st;
    if (stat(dirname(copy), &st) != 0) { /* nothing served there (yet), or a server that has stopped */
        complain(p, "nothing is served there (is `biotac-bench cheetah serve` running?)");
        return NULL;
    }
    if (!S_ISDIR(st.st_mode) || st.st_uid != getuid() || (st.st_mode & 077)) {
        complain(p, "its folder must be yours and private (mode 0700)");
        return NULL;
    }
    return p;
}

static int connect_server(void) {
    const char *path = socket_path();
    if (!path) return -1;
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    strncpy(addr.sun_path, path, sizeof addr.sun_path - 1);
    if (connect(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        complain(path, "nothing is served there (is `biotac-bench cheetah serve` running?)");
        close(fd);
        return -1;
    }
    struct ucred cred;
    socklen_t len = sizeof cred;
    if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0 || cred.uid != getuid()) {
        complain(path, "served by another user");
        close(fd);
        return -1;
    }
    return fd;
}

static int send_all(int fd, const void *buf, size_t n) {
    const u08 *p = buf;
    while (n) {
        ssize_t k = send(fd, p, n, MSG_NOSIGNAL); /* a closed server: EPIPE, never SIGPIPE */
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return -1;
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

static int recv_all(int fd, void *buf, size_t n) {
    u08 *p = buf;
    while (n) {
        ssize_t k = recv(fd, p, n, 0);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return -1;
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

static void put32(u08 *p, u32 v) { p[0] = (u08)v; p[1] = (u08)(v >> 8); p[2] = (u08)(v >> 16); p[3] = (u08)(v >> 24); }
static u32 get32(const u08 *p) { return (u32)p[0] | (u32)p[1] << 8 | (u32)p[2] << 16 | (u32)p[3] << 24; }

static int fail(void) {
    if (dev.open && !dev.broken) { close(dev.fd); dev.fd = -1; dev.broken = 1; }
    return CH_COMMUNICATION_ERROR;
}

/* request: u08 type, u32 length, payload */
static int send_request(int fd, u08 type, const u08 *payload, u32 len) {
    u08 head[5] = {type};
    put32(head + 1, len);
    if (send_all(fd, head, 5) || (len && send_all(fd, payload, len))) return -1;
    return 0;
}

/* reply: u32 length, payload (copied into reply up to cap; *got = full length) */
static int recv_reply(int fd, u08 *reply, u32 cap, u32 *got) {
    u08 rl[4];
    if (recv_all(fd, rl, 4)) return -1;
    u32 n = get32(rl);
    if (n > (64u << 20)) return -1;
    u08 *tmp = malloc(n ? n : 1);
    if (!tmp) return -1;
    if (n && recv_all(fd, tmp, n)) { free(tmp); return -1; }
    u32 k = n < cap ? n : cap;
    if (reply && k) memcpy(reply, tmp, k);
    if (got) *got = n;
    free(tmp);
    return 0;
}

static int request(u08 type, const u08 *payload, u32 len, u08 *reply, u32 cap, u32 *got) {
    if (dev.broken) return CH_COMMUNICATION_ERROR;
    if (send_request(dev.fd, type, payload, len) || recv_reply(dev.fd, reply, cap, got)) return fail();
    return CH_OK;
}

/* ---- the queue ------------------------------------------------------------------------------------------ */
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
    u08 rec[5] = {kind};
    put32(rec + 1, value);
    return push(q, rec, 5);
}

/* A delay longer than one record holds (u32 ns, ~4.29 s) goes in as several records. */
static int push_delay(Queue *q, unsigned long long ns) {
    while (ns) {
        u32 part = ns > UINT32_MAX ? UINT32_MAX : (u32)ns;
        if (push_op(q, OP_DELAY_NS, part)) return -1;
        ns -= part;
    }
    return 0;
}

static int valid(int handle) { return handle == 1 && dev.open; }

/* A batch for the adapter: bit rate kHz u32, mode u08, ss polarity u08, then the op records. */
static u08 *batch_payload(const Queue *q, u32 *len) {
    u08 *payload = malloc(6 + q->len);
    if (!payload) return NULL;
    put32(payload, (u32)dev.bitrate_khz);
    payload[4] = dev.mode;
    payload[5] = dev.ss_polarity;
    memcpy(payload + 6, q->data, q->len);
    *len = (u32)(6 + q->len);
    return payload;
}

static int shift(const Queue *q, int num_bytes, u08 *data_in) {
    if (q->len == 0) return CH_SPI_BATCH_EMPTY_QUEUE;
    if (dev.broken) return CH_COMMUNICATION_ERROR;
    u32 len, got = 0;
    u08 *payload = batch_payload(q, &len);
    if (!payload) return CH_COMMUNICATION_ERROR;
    int cap = num_bytes < 0 ? 0 : num_bytes;
    int st = request(REQ_SHIFT, payload, len, data_in, (u32)cap, &got);
    free(payload);
    if (st != CH_OK) return st;
    return (int)(got < (u32)cap ? got : (u32)cap);
}

/* ---- exported API: ch_c_version and c_ch_* ---------------------------------------------------- */
u32 ch_c_version(void) { return (OLDEST_CLIENT_API << 16) | LIB_VERSION; }

int c_ch_find_devices_ext(int num_devices, u16 *devices, int num_ids, u32 *unique_ids) {
    int in_use = 1;
    if (!dev.open) {
        int fd = connect_server();
        if (fd < 0) return 0;
        u08 reply[5];
        u32 got = 0;
        if (send_request(fd, REQ_QUERY, 0, 0) || recv_reply(fd, reply, sizeof reply, &got) || got < 1) {
            close(fd);
            return 0;
        }
        close(fd);
        in_use = reply[0] != 0;
    }
    if (devices && num_devices > 0) devices[0] = in_use ? (u16)CH_PORT_NOT_FREE : 0;
    if (unique_ids && num_ids > 0) unique_ids[0] = UNIQUE_ID;
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
    u08 status = 1;
    u32 got = 0;
    if (send_request(fd, REQ_HELLO, 0, 0) || recv_reply(fd, &status, 1, &got) || got < 1 || status != 0) {
        close(fd); /* another program has the adapter open */
        return CH_UNABLE_TO_OPEN;
    }
    memset(&dev, 0, sizeof dev);
    dev.fd = fd;
    dev.open = 1;
    dev.bitrate_khz = 1000;
    if (ext) { fill_version(&ext->version); ext->features = 1; }
    return 1;
}

int c_ch_open(int port_number) { return c_ch_open_ext(port_number, 0); }

int c_ch_close(int handle) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (!dev.broken) close(dev.fd);
    free(dev.queue.data);
    memset(&dev, 0, sizeof dev);
    return CH_OK;
}

int c_ch_port(int handle) { return valid(handle) ? 0 : CH_INVALID_HANDLE; }
u32 c_ch_unique_id(int handle) { return valid(handle) ? UNIQUE_ID : 0; }

const char *c_ch_status_string(int status) {
    switch (status) {
    case 0: return "ok";
    case -1: return "unable to load library";
    case -2: return "unable to load USB driver";
    case -3: return "unable to load binding function";
    case -4: return "incompatible library version";
    case -5: return "incompatible device version";
    case -6: return "incompatible driver version";
    case -7: return "communication error (the emulator's Cheetah server went away or is not running)";
    case -8: return "unable to open device";
    case -9: return "unable to close device";
    case -10: return "invalid device handle";
    case -11: return "configuration error";
    case -12: return "unknown protocol";
    case -13: return "device still active";
    case -14: return "function not available";
    case -15: return "OS error";
    case -100: return "SPI write error";
    case -101: return "batch: empty queue";
    case -102: return "batch: short buffer";
    case -103: return "async: nothing to collect";
    case -104: return "async: batches pending";
    case -105: return "async: too many batches submitted";
    case -106: return "async: excess delay";
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
    if (dev.open) { /* the adapter's (virtual) time */
        u08 p[4];
        put32(p, milliseconds);
        if (request(REQ_SLEEP, p, 4, 0, 0, 0) != CH_OK) return 0; /* refused or gone: nothing slept */
    } else { /* no adapter: an ordinary sleep, as the vendor library does */
        struct timespec ts = {(time_t)(milliseconds / 1000), (long)(milliseconds % 1000) * 1000000L};
        while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {}
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
    if ((polarity != 0 && polarity != 1) || (phase != 0 && phase != 1) || (bitorder != 0 && bitorder != 1))
        return CH_CONFIG_ERROR;
    /* the adapter clocks the bus as configured: the sensors speak mode 0, MSB first, active-low selects */
    dev.mode = (u08)(polarity | phase << 1 | bitorder << 2);
    dev.ss_polarity = ss_polarity & 7;
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
    if (push_op(&dev.queue, OP_DELAY_NS, (u32)nanoseconds)) return CH_COMMUNICATION_ERROR;
    return nanoseconds;
}

int c_ch_spi_queue_delay_cycles(int handle, int cycles) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (cycles <= 0) return 0;
    if (push_delay(&dev.queue, (unsigned long long)((long long)cycles * 1000000LL / dev.bitrate_khz)))
        return CH_COMMUNICATION_ERROR;
    return cycles;
}

int c_ch_spi_queue_ss(int handle, u08 active) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    return push_op(&dev.queue, OP_SS, active & 7) ? CH_COMMUNICATION_ERROR : CH_OK;
}

int c_ch_spi_queue_array(int handle, int num_bytes, const u08 *data_out) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (num_bytes <= 0 || !data_out) return 0;
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
    if (dev.async_count) return CH_SPI_ASYNC_PENDING;
    return shift(&dev.queue, num_bytes, data_in);
}

int c_ch_spi_async_submit(int handle) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (dev.async_count >= MAX_ASYNC) return CH_SPI_ASYNC_MAX_REACHED;
    if (dev.queue.len == 0) return CH_SPI_BATCH_EMPTY_QUEUE;
    if (dev.broken) return CH_COMMUNICATION_ERROR;
    u32 len;
    u08 *payload = batch_payload(&dev.queue, &len);
    if (!payload) return CH_COMMUNICATION_ERROR;
    int bad = send_request(dev.fd, REQ_SUBMIT, payload, len); /* it starts now; collect waits for the result */
    free(payload);
    if (bad) return fail();
    dev.async_count++;
    return CH_OK;
}

int c_ch_spi_async_collect(int handle, int num_bytes, u08 *data_in) {
    if (!valid(handle)) return CH_INVALID_HANDLE;
    if (dev.async_count == 0) return CH_SPI_ASYNC_EMPTY;
    dev.async_count--;
    u32 got = 0;
    int cap = num_bytes < 0 ? 0 : num_bytes;
    int st = request(REQ_COLLECT, 0, 0, data_in, (u32)cap, &got);
    if (st != CH_OK) return st;
    return (int)(got < (u32)cap ? got : (u32)cap);
}
