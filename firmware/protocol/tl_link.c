/* SPDX-License-Identifier: MIT */
/* COBS framing, CRC and replay guard of the link (docs/protocol.md). */
#include "tl_link.h"

/* CRC-16/CCITT-FALSE a nibble at a time: a 32-byte table, about a quarter of
 * the cycles of the bitwise loop (frame encoding runs beside the control loop). */
static const uint16_t crc_nibble[16] = {
    0x0000, 0x1021, 0x2042, 0x3063, 0x4084, 0x50A5, 0x60C6, 0x70E7,
    0x8108, 0x9129, 0xA14A, 0xB16B, 0xC18C, 0xD1AD, 0xE1CE, 0xF1EF,
};

uint16_t tl_crc16(const uint8_t *data, size_t len, uint16_t crc)
{
    for (size_t i = 0; i < len; i++) {
        crc = (uint16_t)((crc << 4) ^ crc_nibble[((crc >> 12) ^ (data[i] >> 4)) & 0xFu]);
        crc = (uint16_t)((crc << 4) ^ crc_nibble[((crc >> 12) ^ (data[i] & 0xFu)) & 0xFu]);
    }
    return crc;
}

int32_t tl_cobs_decode(const uint8_t *src, size_t len, uint8_t *dst, size_t dst_cap)
{
    size_t i = 0, o = 0;
    while (i < len) {
        uint8_t code = src[i];
        if (code == 0u || i + code > len)
            return -1;
        for (size_t k = 1; k < code; k++) {
            if (src[i + k] == 0u || o >= dst_cap)
                return -1;
            dst[o++] = src[i + k];
        }
        i += code;
        if (code < 0xFFu && i < len) {
            if (o >= dst_cap)
                return -1;
            dst[o++] = 0u;
        }
    }
    return (int32_t)o;
}

size_t tl_cobs_encode(const uint8_t *src, size_t len, uint8_t *dst)
{
    size_t code_at = 0, o = 1;
    uint8_t code = 1;
    for (size_t i = 0; i < len; i++) {
        if (src[i] == 0u) {
            dst[code_at] = code;
            code_at = o++;
            code = 1;
        } else {
            dst[o++] = src[i];
            if (++code == 0xFFu) {
                dst[code_at] = code;
                code_at = o++;
                code = 1;
            }
        }
    }
    dst[code_at] = code;
    return o;
}

void tl_rx_init(tl_rx_t *rx)
{
    rx->len = 0;
    rx->overflow = false;
}

static tl_rx_result_t check(const tl_rx_t *rx, tl_frame_t *out, uint8_t *status)
{
    uint8_t pkt[TLP_MAX_PACKET];
    int32_t n = tl_cobs_decode(rx->buf, rx->len, pkt, sizeof pkt);
    if (n < 0) {
        /* Valid COBS that only failed for room is an oversize frame, not noise. */
        uint8_t big[2 * TLP_MAX_ENCODED];
        *status = (tl_cobs_decode(rx->buf, rx->len, big, sizeof big) > (int32_t)TLP_MAX_PACKET)
                      ? TLP_ST_OVERSIZE : TLP_ST_FRAMING;
        return TL_RX_ERROR;
    }
    if (n < (int32_t)(TLP_HEADER_BYTES + TLP_CRC_BYTES)) {
        *status = TLP_ST_FRAMING;
        return TL_RX_ERROR;
    }
    size_t body = (size_t)n - TLP_CRC_BYTES;
    if (tl_crc16(pkt, body, 0xFFFFu) != tl_get_u16(&pkt[body])) {
        *status = TLP_ST_CRC;
        return TL_RX_ERROR;
    }
    if (pkt[3] != body - TLP_HEADER_BYTES) {
        *status = TLP_ST_LENGTH;
        return TL_RX_ERROR;
    }
    out->seq = tl_get_u16(pkt);
    out->cmd = pkt[2];
    out->len = pkt[3];
    for (size_t i = 0; i < out->len; i++)
        out->payload[i] = pkt[TLP_HEADER_BYTES + i];
    return TL_RX_FRAME;
}

tl_rx_result_t tl_rx_byte(tl_rx_t *rx, uint8_t byte, tl_frame_t *out, uint8_t *status)
{
    if (byte != 0u) {
        if (rx->len < TLP_MAX_ENCODED)
            rx->buf[rx->len++] = byte;
        else
            rx->overflow = true;
        return TL_RX_NONE;
    }
    tl_rx_result_t r = TL_RX_NONE;
    if (rx->overflow) {
        *status = TLP_ST_OVERSIZE;
        r = TL_RX_ERROR;
    } else if (rx->len > 0u) {
        r = check(rx, out, status);
    }
    tl_rx_init(rx);
    return r;
}

size_t tl_frame_encode(uint16_t seq, uint8_t cmd, const uint8_t *payload, uint8_t len,
                       uint8_t *wire, size_t cap)
{
    uint8_t pkt[TLP_MAX_PACKET];
    if (len > TLP_MAX_PAYLOAD || cap < TLP_MAX_WIRE)
        return 0;
    tl_put_u16(pkt, seq);
    pkt[2] = cmd;
    pkt[3] = len;
    for (size_t i = 0; i < len; i++)
        pkt[TLP_HEADER_BYTES + i] = payload[i];
    size_t body = TLP_HEADER_BYTES + (size_t)len;
    tl_put_u16(&pkt[body], tl_crc16(pkt, body, 0xFFFFu));
    /* 0x00 on both sides: bytes a bridge inserted before the frame end as their own chunk */
    wire[0] = 0u;
    size_t n = 1u + tl_cobs_encode(pkt, body + TLP_CRC_BYTES, &wire[1]);
    wire[n++] = 0u;
    return n;
}

bool tl_seq_is_new(const tl_seq_t *s, uint16_t seq)
{
    if (!s->any)
        return true;
    uint16_t ahead = (uint16_t)(seq - s->last);
    return ahead != 0u && ahead < TLP_SEQ_WINDOW;
}

void tl_seq_accept(tl_seq_t *s, uint16_t seq)
{
    s->last = seq;
    s->any = true;
}
