/* BioTac bridge firmware: samples 1..5 sensors over SPI and streams frames over a UART.
 *
 * UART framing, both directions:  0xAA 0x55 | type u8 | length u16 LE | payload | CRC-16/CCITT-FALSE u16 LE
 * (the CRC covers type, length and payload).
 *   firmware -> host   0x10 DATA    seq u16, sensor mask u8, slots u8, then per slot: channel u8 and, per
 *                                   present sensor in ascending order, u16 = code (12 bits) | status << 12
 *                                   (status 0 ok, 1 parity error, 2 error word from the sensor)
 *                      0x11 STATUS  mask u8, streaming u8, frames u32, parity errors u32, error words u32,
 *                                   sensor losses u32, sensor finds u32, command errors u32, SP mask u8
 *                                   (bit i: sensor i + 1's serial starts "BTSP", a 24-electrode BioTac SP)
 *                      0x12 ACK     command type u8, result u8 (0 ok, 1 bad length, 2 unknown, 3 bad value)
 *   host -> firmware   0x01 START, 0x02 STOP, 0x03 PATTERN (payload: 1..64 channel indices), 0x04 STATUS
 *                      A frame with more than 64 payload bytes is answered ACK 1 (bad length) whatever its
 *                      type, if its CRC holds; a valid frame inside it is served and ends it (a corrupted
 *                      length delays no command).  Bytes skipped as garbage count as command errors.
 *
 * Default pattern: the 54-slot SP frame (E1,PAC,...,E24,PAC,PDC,PAC,TAC,PAC,TDC,PAC) when every sensor present
 * is a BioTac SP, else the 44-slot frame (E1..E19) every variant answers; re-chosen at each detection until
 * the host sets a pattern.  A channel a sensor does not have (E20..E24 on a 19-electrode BioTac) comes back
 * as its "EX" error word: status 2, never a code.
 */
#ifndef BT_BRIDGE_H
#define BT_BRIDGE_H
#include "bt_hal.h"

#define BT_MAX_SENSORS 5
#define BT_MAX_PATTERN 64
#define BT_LONG_FOLLOWS 4  /* over-long frames followed at once */

/* A frame announcing more payload than BT_MAX_PATTERN, followed byte by byte as it passes. */
typedef struct {
    uint32_t left;            /* its bytes still to come (payload, then CRC) */
    uint32_t errors_before;   /* command errors pending when it began (garbage before it) */
    uint16_t crc;             /* running CRC over type, length and the payload so far */
    uint16_t tail;            /* the CRC bytes received */
    uint8_t type;
} bt_long_frame;

typedef struct {
    const bt_hal *hal;
    uint8_t present;          /* bit i: sensor i + 1 answers with a serial number starting "BT" */
    uint8_t sp;               /* bit i: ... starting "BTSP" (a BioTac SP, E1..E24) */
    uint8_t pattern_default;  /* the pattern is the default one (follows the sensors' variants) */
    uint8_t streaming;
    uint8_t pattern[BT_MAX_PATTERN];
    uint8_t pattern_len;
    uint16_t seq;
    uint32_t frames, parity_errors, error_words, losses, finds, cmd_errors;
    uint32_t frames_since_detect;
    uint8_t absent_streak[BT_MAX_SENSORS];
    /* host command parser */
    uint8_t rx[4 + 2 + BT_MAX_PATTERN + 2];
    size_t rx_len;
    /* over-long frames being followed as they pass (longer than rx can hold) */
    bt_long_frame longs[BT_LONG_FOLLOWS];
    uint8_t long_n;           /* how many */
    uint32_t long_dropped;    /* bytes the parser dropped meanwhile: errors unless one of them is answered */
} bt_bridge;

void bt_init(bt_bridge *b, const bt_hal *hal);
/* One pass of the main loop: serve host commands, then stream one frame (or idle for 1 ms). */
void bt_step(bt_bridge *b);
/* Look for sensors (serial number "BT..."); returns the mask of present sensors. */
uint8_t bt_detect(bt_bridge *b);
uint16_t bt_crc16(const uint8_t *data, size_t n);
/* Set the sampling pattern (what the PATTERN command does): 1..64 channel indices, each 0..3 or 17..40.
 * Returns the ACK result: 0 ok, 1 bad length, 3 bad value (the pattern is then unchanged). */
uint8_t bt_set_pattern(bt_bridge *b, const uint8_t *p, size_t len);

#endif
