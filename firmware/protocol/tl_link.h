/* SPDX-License-Identifier: MIT */
/* Link layer of the torqueloop protocol (docs/protocol.md): COBS framing,
 * CRC-16/CCITT-FALSE, length and sequence checks.  Plain C11 with no
 * hardware access, so the same file runs on the soft CPU, in the host unit
 * tests and under the fuzzer. */
#ifndef TL_LINK_H
#define TL_LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tl_protocol.h"

typedef struct {
    uint8_t buf[TLP_MAX_ENCODED];  /* COBS bytes of the frame being received */
    uint32_t len;
    bool overflow;                 /* more than TLP_MAX_ENCODED bytes before the delimiter */
} tl_rx_t;

typedef struct {
    uint16_t seq;
    uint8_t cmd;
    uint8_t len;
    uint8_t payload[TLP_MAX_PAYLOAD];
} tl_frame_t;

typedef enum { TL_RX_NONE, TL_RX_FRAME, TL_RX_ERROR } tl_rx_result_t;

uint16_t tl_crc16(const uint8_t *data, size_t len, uint16_t crc);
/* Returns the decoded length, or -1 if src is not valid COBS or does not fit dst_cap. */
int32_t tl_cobs_decode(const uint8_t *src, size_t len, uint8_t *dst, size_t dst_cap);
/* Returns the encoded length (no delimiter); dst needs len + len / 254 + 1 bytes. */
size_t tl_cobs_encode(const uint8_t *src, size_t len, uint8_t *dst);

void tl_rx_init(tl_rx_t *rx);
/* Feed one received byte.  On a delimiter: TL_RX_FRAME with *out filled, or
 * TL_RX_ERROR with *status set (TLP_ST_CRC, FRAMING, LENGTH, OVERSIZE);
 * empty chunks (two delimiters in a row) give TL_RX_NONE. */
tl_rx_result_t tl_rx_byte(tl_rx_t *rx, uint8_t byte, tl_frame_t *out, uint8_t *status);
/* Encode a frame into wire bytes (0x00, COBS, 0x00; cap >= TLP_MAX_WIRE); returns the byte count. */
size_t tl_frame_encode(uint16_t seq, uint8_t cmd, const uint8_t *payload, uint8_t len,
                       uint8_t *wire, size_t cap);

/* Replay guard: a command is new if seq is in (last, last + TLP_SEQ_WINDOW). */
typedef struct {
    uint16_t last;
    bool any;     /* false until the first accepted command after reset */
} tl_seq_t;

bool tl_seq_is_new(const tl_seq_t *s, uint16_t seq);
void tl_seq_accept(tl_seq_t *s, uint16_t seq);

static inline uint16_t tl_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t tl_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline void tl_put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void tl_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}

#endif
