/* SPDX-License-Identifier: MIT */
/* Authenticated sessions of the link (tl_auth.h, docs/security.md). */
#include "tl_auth.h"

#include "tl_keyslot.h"

#define LABEL TLP_AUTH_LABEL_BYTES

/* memcpy (firmware/common/mem.c on the CPU): one call instead of an inlined loop each time */
#define copy(dst, src, n) __builtin_memcpy((dst), (src), (n))

void tl_auth_init(tl_auth_t *a, const uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES])
{
    a->have_key = false;
    a->open = false;
    a->started = false;
    a->base = 0;
    a->last_off = 0;
    a->count = 0;
    __builtin_memset(a->pool, 0, sizeof a->pool);
    a->have_key = tl_keyslot_load(slot, &a->key);
}

uint8_t tl_auth_session(tl_auth_t *a, const uint8_t host_nonce[TLP_AUTH_NONCE_BYTES], uint32_t cycles,
                        uint8_t board_nonce[TLP_AUTH_NONCE_BYTES], uint8_t proof[TLP_AUTH_TAG_BYTES])
{
    if (!a->have_key)
        return TLP_ST_NO_KEY;
    uint8_t msg[LABEL + TL_SHA256_BYTES + 12u + TLP_AUTH_NONCE_BYTES];
    copy(msg, (const uint8_t *)TLP_AUTH_LABEL_NONCE, LABEL);
    copy(&msg[LABEL], a->pool, TL_SHA256_BYTES);
    tl_put_u32(&msg[LABEL + 32u], a->count);
    tl_put_u32(&msg[LABEL + 36u], cycles);
    tl_put_u32(&msg[LABEL + 40u], a->stir);
    copy(&msg[LABEL + 44u], host_nonce, TLP_AUTH_NONCE_BYTES);
    tl_hmac(&a->key, msg, sizeof msg, a->pool);
    a->count++;
    copy(a->board_nonce, a->pool, TLP_AUTH_NONCE_BYTES);
    copy(a->host_nonce, host_nonce, TLP_AUTH_NONCE_BYTES);
    a->open = true;
    a->started = false;
    a->last_off = 0;

    uint8_t pm[LABEL + 2u * TLP_AUTH_NONCE_BYTES], mac[TL_SHA256_BYTES];
    copy(pm, (const uint8_t *)TLP_AUTH_LABEL_PROOF, LABEL);
    copy(&pm[LABEL], host_nonce, TLP_AUTH_NONCE_BYTES);
    copy(&pm[LABEL + TLP_AUTH_NONCE_BYTES], a->board_nonce, TLP_AUTH_NONCE_BYTES);
    tl_hmac(&a->key, pm, sizeof pm, mac);
    copy(board_nonce, a->board_nonce, TLP_AUTH_NONCE_BYTES);
    copy(proof, mac, TLP_AUTH_TAG_BYTES);
    return TLP_ST_OK;
}

void tl_auth_tag(const tl_auth_t *a, uint16_t seq, uint8_t cmd, const uint8_t *payload, uint8_t payload_len,
                 uint8_t tag[TLP_AUTH_TAG_BYTES])
{
    uint8_t head[LABEL + 2u * TLP_AUTH_NONCE_BYTES + TLP_HEADER_BYTES], mac[TL_SHA256_BYTES];
    copy(head, (const uint8_t *)TLP_AUTH_LABEL_FRAME, LABEL);
    copy(&head[LABEL], a->board_nonce, TLP_AUTH_NONCE_BYTES);
    copy(&head[LABEL + TLP_AUTH_NONCE_BYTES], a->host_nonce, TLP_AUTH_NONCE_BYTES);
    uint8_t *h = &head[LABEL + 2u * TLP_AUTH_NONCE_BYTES];
    tl_put_u16(h, seq);
    h[2] = cmd;
    h[3] = (uint8_t)(payload_len + TLP_AUTH_TAG_BYTES);
    tl_hmac_t m;
    tl_hmac_init(&m, &a->key);
    tl_hmac_update(&m, head, sizeof head);
    tl_hmac_update(&m, payload, payload_len);
    tl_hmac_final(&m, mac);
    copy(tag, mac, TLP_AUTH_TAG_BYTES);
}

uint8_t tl_auth_verify(tl_auth_t *a, const tl_frame_t *f)
{
    if (!a->have_key)
        return TLP_ST_NO_KEY;
    if (!a->open || f->len < TLP_AUTH_TAG_BYTES)
        return TLP_ST_NO_SESSION;
    uint16_t off = (uint16_t)(f->seq - a->base);
    if (a->started) {
        /* Outside the range no authenticated frame of this session can be:
         * the host has used it up (or moved far ahead) and must open a new one. */
        if (off >= TLP_AUTH_SESSION_WINDOW)
            return TLP_ST_NO_SESSION;
        if (off <= a->last_off)
            return TLP_ST_REPLAY;
    }
    uint8_t len = (uint8_t)(f->len - TLP_AUTH_TAG_BYTES), tag[TLP_AUTH_TAG_BYTES];
    tl_auth_tag(a, f->seq, f->cmd, f->payload, len, tag);
    if (!tl_ct_equal(tag, &f->payload[len], TLP_AUTH_TAG_BYTES))
        return TLP_ST_AUTH;
    if (!a->started) {
        a->started = true;
        a->base = f->seq;
        off = 0;
    }
    a->last_off = off;
    return TLP_ST_OK;
}
