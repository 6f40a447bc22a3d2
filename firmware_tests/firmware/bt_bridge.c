/* BioTac bridge firmware (portable C11). See bt_bridge.h for the UART protocol. */
#include "bt_bridge.h"

#include <string.h>

static const uint8_t SELECT[BT_MAX_SENSORS] = {1, 2, 4, 5, 6};
static const uint8_t DEFAULT_FRAME[44] = {17, 0, 18, 0, 19, 0, 20, 0, 21, 0, 22, 0, 23, 0, 24, 0, 25, 0, 26, 0, 27, 0,
                                          28, 0, 29, 0, 30, 0, 31, 0, 32, 0, 33, 0, 34, 0, 35, 0, 1, 0, 2, 0, 3, 0};
/* The BioTac SP's frame: E1..E24 (channels 17..40) each followed by PAC, then PDC, TAC, TDC: 54 slots. */
static const uint8_t SP_FRAME[54] = {17, 0, 18, 0, 19, 0, 20, 0, 21, 0, 22, 0, 23, 0, 24, 0, 25, 0, 26, 0, 27, 0,
                                     28, 0, 29, 0, 30, 0, 31, 0, 32, 0, 33, 0, 34, 0, 35, 0, 36, 0, 37, 0, 38, 0,
                                     39, 0, 40, 0, 1, 0, 2, 0, 3, 0};
#define LAST_ELECTRODE 40u        /* E24 of the SP; a 19-electrode sensor answers 36..40 with "EX" */
#define SLOT_NS 227273u           /* 4.4 kHz */
#define SAMPLE_DELAY_NS 50000u
#define WORD_NS 3750u             /* 16.5 SCK periods at 4.4 MHz */
#define DETECT_EVERY_FRAMES 100u  /* once a second while streaming */
#define LOST_AFTER_FRAMES 2u

/* CRC-16/CCITT-FALSE, one byte at a time (so a frame too long to keep can be checked as it passes). */
static uint16_t crc16_byte(uint16_t crc, uint8_t byte) {
    crc ^= (uint16_t)byte << 8;
    for (int k = 0; k < 8; ++k) crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021) : (uint16_t)(crc << 1);
    return crc;
}

uint16_t bt_crc16(const uint8_t *data, size_t n) {
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < n; ++i) crc = crc16_byte(crc, data[i]);
    return crc;
}

static int odd_parity(uint8_t byte) {
    int ones = 0;
    for (int k = 0; k < 8; ++k) ones += (byte >> k) & 1;
    return ones & 1;
}

static uint8_t command_byte(uint8_t channel) {
    uint8_t b = (uint8_t)(0x80 | (channel << 1));
    return odd_parity(b) ? b : (uint8_t)(b | 1);
}

static void send(bt_bridge *b, uint8_t type, const uint8_t *payload, uint16_t len) {
    uint8_t head[5] = {0xAA, 0x55, type, (uint8_t)(len & 0xFF), (uint8_t)(len >> 8)};
    uint16_t crc = 0xFFFF;
    /* CRC over type, length, payload: continue the CRC across the two pieces */
    uint8_t tmp[3] = {type, head[3], head[4]};
    crc = bt_crc16(tmp, 3);
    for (uint16_t i = 0; i < len; ++i) crc = crc16_byte(crc, payload[i]);
    uint8_t tail[2] = {(uint8_t)(crc & 0xFF), (uint8_t)(crc >> 8)};
    b->hal->uart_write(b->hal->ctx, head, 5);
    if (len) b->hal->uart_write(b->hal->ctx, payload, len);
    b->hal->uart_write(b->hal->ctx, tail, 2);
}

static void put32(uint8_t *p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = (uint8_t)(v >> (8 * k));
}

static void send_status(bt_bridge *b) {
    uint8_t p[2 + 6 * 4 + 1];
    p[0] = b->present;
    p[1] = b->streaming;
    put32(p + 2, b->frames);
    put32(p + 6, b->parity_errors);
    put32(p + 10, b->error_words);
    put32(p + 14, b->losses);
    put32(p + 18, b->finds);
    put32(p + 22, b->cmd_errors);
    p[26] = b->sp;
    send(b, 0x11, p, sizeof p);
}

static void ack(bt_bridge *b, uint8_t cmd, uint8_t result) {
    uint8_t p[2] = {cmd, result};
    if (result) b->cmd_errors++;
    send(b, 0x12, p, 2);
}

/* Serial number property: read command, wait, then bytes with chip select held until NUL or 0xFF.
 * Returns 0 (no sensor), 1 (a BioTac: "BT...") or 2 (a BioTac SP: "BTSP..."). */
static int has_bt_serial(bt_bridge *b, int sensor) {
    const bt_hal *h = b->hal;
    uint8_t tx[2] = {0x61, 0x15}, rx[2];
    h->spi_bytes(h->ctx, SELECT[sensor], 0, tx, rx, 2);
    h->delay_us(h->ctx, 60);
    char serial[20];
    size_t n = 0;
    uint8_t zero = 0, byte = 0;
    while (n < sizeof serial) {
        h->spi_bytes(h->ctx, SELECT[sensor], 1, &zero, &byte, 1);
        if (byte == 0x00 || byte == 0xFF) break;
        serial[n++] = (char)byte;
    }
    h->spi_bytes(h->ctx, 0, 0, &zero, &byte, 0); /* release chip select */
    h->delay_us(h->ctx, 10);
    if (n < 2 || serial[0] != 'B' || serial[1] != 'T') return 0;
    return (n >= 4 && serial[2] == 'S' && serial[3] == 'P') ? 2 : 1;
}

/* The default pattern for the sensors present: the SP's 54 slots when every one is an SP, else the 44 slots
 * every variant answers. A pattern the host set stays. */
static void choose_default_pattern(bt_bridge *b) {
    if (!b->pattern_default) return;
    if (b->present && (b->present & (uint8_t)~b->sp) == 0) {
        memcpy(b->pattern, SP_FRAME, sizeof SP_FRAME);
        b->pattern_len = sizeof SP_FRAME;
    } else {
        memcpy(b->pattern, DEFAULT_FRAME, sizeof DEFAULT_FRAME);
        b->pattern_len = sizeof DEFAULT_FRAME;
    }
}

uint8_t bt_detect(bt_bridge *b) {
    uint8_t mask = 0, sp = 0;
    for (int s = 0; s < BT_MAX_SENSORS; ++s) {
        int kind = has_bt_serial(b, s);
        if (kind) mask |= (uint8_t)(1u << s);
        if (kind == 2) sp |= (uint8_t)(1u << s);
    }
    for (int s = 0; s < BT_MAX_SENSORS; ++s) {
        uint8_t bit = (uint8_t)(1u << s);
        if ((mask & bit) && !(b->present & bit)) b->finds++;
        if (!(mask & bit) && (b->present & bit)) b->losses++;
        b->absent_streak[s] = 0;
    }
    b->present = mask;
    b->sp = sp;
    b->frames_since_detect = 0;
    choose_default_pattern(b);
    return mask;
}

void bt_init(bt_bridge *b, const bt_hal *hal) {
    memset(b, 0, sizeof *b);
    b->hal = hal;
    memcpy(b->pattern, DEFAULT_FRAME, sizeof DEFAULT_FRAME);
    b->pattern_len = sizeof DEFAULT_FRAME;
    b->pattern_default = 1;
    hal->delay_us(hal->ctx, 1000); /* sensors power up */
    b->finds = 0;
    bt_detect(b);
    b->finds = 0; /* sensors present at start-up are not "found again" */
}

uint8_t bt_set_pattern(bt_bridge *b, const uint8_t *p, size_t len) {
    if (len < 1 || len > BT_MAX_PATTERN) return 1;
    for (size_t i = 0; i < len; ++i)
        if (!(p[i] <= 3 || (p[i] >= 17 && p[i] <= LAST_ELECTRODE))) return 3;
    memcpy(b->pattern, p, len);
    b->pattern_len = (uint8_t)len;
    b->pattern_default = 0;
    return 0;
}

static void handle_command(bt_bridge *b, uint8_t type, const uint8_t *p, uint16_t len) {
    switch (type) {
    case 0x01: b->streaming = 1; ack(b, type, 0); break;
    case 0x02: b->streaming = 0; ack(b, type, 0); break;
    case 0x03: ack(b, type, bt_set_pattern(b, p, len)); break;
    case 0x04: send_status(b); break;
    default: ack(b, type, 2); break;
    }
}

/* A byte the parser drops as garbage: a command error, unless over-long frames are being followed (their own
 * bytes are dropped too, and count only if none turns out to be a frame). */
static void count_dropped(bt_bridge *b) {
    if (b->long_n) b->long_dropped++;
    else b->cmd_errors++;
}

/* Stop following every over-long frame without answering: the bytes dropped meanwhile were garbage after all. */
static void abandon_long_frames(bt_bridge *b) {
    b->cmd_errors += b->long_dropped;
    b->long_dropped = 0;
    b->long_n = 0;
}

/* Take one byte of an over-long frame: 0 while it goes on, 1 at its last byte if its CRC holds, -1 if not. */
static int long_frame_byte(bt_long_frame *f, uint8_t byte) {
    if (f->left > 2) f->crc = crc16_byte(f->crc, byte);
    else f->tail |= (uint16_t)(byte << (f->left == 2 ? 0 : 8));
    if (--f->left) return 0;
    return f->tail == f->crc ? 1 : -1;
}

/* The header at rx[0] announces more payload than BT_MAX_PATTERN: follow that frame as its bytes pass, without
 * keeping them, with a running CRC (from the bytes already received behind the header on), so that a frame the
 * firmware cannot hold is still answered (ACK 1, bad length).  Up to BT_LONG_FOLLOWS at once: a stray header
 * announcing a long frame does not hide a genuine one starting inside it. */
static void follow_long_frame(bt_bridge *b, uint16_t len) {
    if (b->long_n >= BT_LONG_FOLLOWS) return;
    bt_long_frame *f = &b->longs[b->long_n++];
    f->left = (uint32_t)len + 2;
    f->crc = bt_crc16(b->rx + 2, 3);
    f->tail = 0;
    f->type = b->rx[2];
    f->errors_before = b->long_dropped;
    for (size_t i = 5; i < b->rx_len; ++i) /* at most 66 bytes: rx never holds a whole long frame (>= 72) */
        (void)long_frame_byte(f, b->rx[i]);
}

/* Whether a complete frame whose CRC holds ends with the newest byte of the receive buffer, behind its start: the
 * header at the start, still waiting for its bytes, is then garbage (a corrupted length) and must not hold up the
 * frame behind it.  (A valid frame ending earlier was found when its last byte came.) */
static int valid_frame_ends_here(const bt_bridge *b) {
    for (size_t j = 1; j + 7 <= b->rx_len; ++j) {
        if (b->rx[j] != 0xAA || b->rx[j + 1] != 0x55) continue;
        uint16_t len = (uint16_t)(b->rx[j + 3] | (b->rx[j + 4] << 8));
        if (len > BT_MAX_PATTERN || j + 7 + len != b->rx_len) continue;
        uint16_t crc = (uint16_t)(b->rx[j + 5 + len] | (b->rx[j + 6 + len] << 8));
        if (crc == bt_crc16(b->rx + j + 2, 3 + (size_t)len)) return 1;
    }
    return 0;
}

/* Parse one byte into the receive buffer; returns 1 if it completed a valid frame (which is served). */
static int parse_byte(bt_bridge *b, uint8_t byte) {
    if (b->rx_len >= sizeof b->rx) { /* cannot be a frame: drop the oldest byte */
        memmove(b->rx, b->rx + 1, --b->rx_len);
        count_dropped(b);
    }
    b->rx[b->rx_len++] = byte;
    for (;;) {
        if (b->rx_len >= 1 && b->rx[0] != 0xAA) goto drop;
        if (b->rx_len >= 2 && b->rx[1] != 0x55) goto drop;
        if (b->rx_len < 5) return 0;
        uint16_t len = (uint16_t)(b->rx[3] | (b->rx[4] << 8));
        if (len > BT_MAX_PATTERN) {
            follow_long_frame(b, len);
            goto drop;
        }
        if (b->rx_len < (size_t)(5 + len + 2)) {
            if (valid_frame_ends_here(b)) goto drop;
            return 0;
        }
        uint16_t crc = (uint16_t)(b->rx[5 + len] | (b->rx[6 + len] << 8));
        if (crc != bt_crc16(b->rx + 2, 3 + len)) goto drop;
        abandon_long_frames(b); /* a valid frame inside long ones ends them; their garbage was garbage */
        handle_command(b, b->rx[2], b->rx + 5, len);
        b->rx_len = 0;
        return 1;
    drop:
        memmove(b->rx, b->rx + 1, --b->rx_len);
        count_dropped(b);
    }
}

/* One byte from the host: the over-long frames followed take it, then the parser; a valid frame it completes is
 * served (and ends the long ones), else a long frame it ended with a good CRC is answered ACK 1 and its bytes
 * held in rx are dropped with it. */
static void serve_byte(bt_bridge *b, uint8_t byte) {
    bt_long_frame ended = {0};
    int answered = 0, following = b->long_n > 0;
    for (uint8_t k = 0; k < b->long_n; ++k)
        if (long_frame_byte(&b->longs[k], byte) > 0 && !answered) {
            answered = 1;
            ended = b->longs[k];
        }
    int served = parse_byte(b, byte); /* (frames this byte ended still hold what it drops as theirs) */
    uint8_t kept = 0;
    for (uint8_t k = 0; k < b->long_n; ++k)
        if (b->longs[k].left) b->longs[kept++] = b->longs[k];
    b->long_n = kept;
    if (served) return;
    if (answered) {
        b->cmd_errors += ended.errors_before; /* garbage before it; its own bytes are no errors */
        b->long_dropped = 0;
        b->long_n = 0;
        b->rx_len = 0;
        ack(b, ended.type, 1);
    } else if (following && !b->long_n) {
        abandon_long_frames(b);
    }
}

/* Host commands arrive as frames; garbage is skipped byte by byte until a valid frame parses.  A header whose
 * length is corrupted delays no command behind it: while a frame waits for its bytes, a complete valid frame
 * behind its start wins, and frames longer than the receive buffer are followed as they pass (follow_long_frame)
 * while the parser goes on looking for frames among their bytes; a valid frame among them is served and ends them. */
static void serve_host(bt_bridge *b) {
    uint8_t buf[64];
    size_t n;
    while ((n = b->hal->uart_read(b->hal->ctx, buf, sizeof buf)) > 0)
        for (size_t i = 0; i < n; ++i) serve_byte(b, buf[i]);
}

static void stream_frame(bt_bridge *b) {
    const bt_hal *h = b->hal;
    uint8_t sensors[BT_MAX_SENSORS];
    int ns = 0;
    for (int s = 0; s < BT_MAX_SENSORS; ++s)
        if (b->present & (1u << s)) sensors[ns++] = (uint8_t)s;
    if (ns == 0) { h->delay_us(h->ctx, 10000); return; }
    static bt_word words[BT_MAX_PATTERN * (1 + BT_MAX_SENSORS)];
    static uint16_t miso[BT_MAX_PATTERN * (1 + BT_MAX_SENSORS)];
    size_t w = 0;
    uint8_t broadcast = ns == 1 ? SELECT[sensors[0]] : 7;
    for (int k = 0; k < b->pattern_len; ++k) {
        uint32_t t = (uint32_t)((uint64_t)k * 1000000000u / 4400u);
        words[w++] = (bt_word){t, broadcast, 0, (uint16_t)(command_byte(b->pattern[k]) << 8)};
        t += WORD_NS + SAMPLE_DELAY_NS;
        for (int i = 0; i < ns; ++i, t += WORD_NS)
            words[w++] = (bt_word){t, SELECT[sensors[i]], (uint8_t)(i + 1 < ns), 0x0000};
    }
    h->spi_sequence(h->ctx, words, miso, w);
    /* pad to the end of the frame's last slot */
    uint64_t frame_end_ns = (uint64_t)b->pattern_len * 1000000000u / 4400u;
    uint32_t used_ns = words[w - 1].offset_ns + WORD_NS;
    if (frame_end_ns > used_ns) h->delay_us(h->ctx, (uint32_t)((frame_end_ns - used_ns) / 1000u));

    static uint8_t payload[4 + BT_MAX_PATTERN * (1 + 2 * BT_MAX_SENSORS)];
    size_t p = 0;
    payload[p++] = (uint8_t)(b->seq & 0xFF);
    payload[p++] = (uint8_t)(b->seq >> 8);
    payload[p++] = b->present;
    payload[p++] = b->pattern_len;
    int absent_words[BT_MAX_SENSORS] = {0};
    size_t r = 0;
    for (int k = 0; k < b->pattern_len; ++k) {
        payload[p++] = b->pattern[k];
        r++; /* the broadcast command's MISO is ignored */
        for (int i = 0; i < ns; ++i, ++r) {
            uint16_t word = miso[r];
            uint8_t b0 = (uint8_t)(word >> 8), b1 = (uint8_t)(word & 0xFF);
            uint16_t code = (uint16_t)((b0 >> 1) * 32 + (b1 >> 3));
            uint8_t status = 0;
            if (b0 == 0xA5) { status = 2; b->error_words++; }
            else if (!odd_parity(b0) || !odd_parity(b1)) { status = 1; b->parity_errors++; }
            if (word == 0x0000 || word == 0xFFFF) absent_words[i]++;
            uint16_t v = (uint16_t)((code & 0x0FFF) | (status << 12));
            payload[p++] = (uint8_t)(v & 0xFF);
            payload[p++] = (uint8_t)(v >> 8);
        }
    }
    send(b, 0x10, payload, (uint16_t)p);
    b->seq++;
    b->frames++;
    /* a sensor that answered nothing but an idle line for whole frames is gone: look for it again later */
    int lost = 0;
    for (int i = 0; i < ns; ++i) {
        if (absent_words[i] == b->pattern_len) {
            if (++b->absent_streak[sensors[i]] >= LOST_AFTER_FRAMES) lost = 1;
        } else {
            b->absent_streak[sensors[i]] = 0;
        }
    }
    if (lost || ++b->frames_since_detect >= DETECT_EVERY_FRAMES) bt_detect(b);
}

void bt_step(bt_bridge *b) {
    serve_host(b);
    if (b->streaming) stream_frame(b);
    else b->hal->delay_us(b->hal->ctx, 1000);
}

/* For hosts that allocate the firmware's state themselves (the bench's co-simulation). */
size_t bt_bridge_size(void) { return sizeof(bt_bridge); }
