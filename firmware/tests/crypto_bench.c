/* SPDX-License-Identifier: MIT */
/* The cost of authentication on the soft CPU (scripts/benches/bench_auth.py
 * runs this on the CPU's RTL through scripts/run_elf.py): mcycle around the
 * firmware's own code - the check of one authenticated frame as servo.c
 * runs it (tl_auth_verify of a tagged SET_PARAM), a SESSION, HMAC-SHA-256
 * and SipHash-2-4 over the same frame message and over 1 KiB and 4 KiB -
 * written to the signature with the MACs, which the bench compares with
 * Python's hmac and torqueloop.spec.auth.siphash24 (the RTL must compute
 * what the host does). */
#include <stdint.h>

#include "tl_auth.h"
#include "tl_sha256.h"
#include "tl_siphash.h"

enum {
    S_SHA_BLOCK, S_VERIFY, S_SESSION, S_HMAC_1K, S_HMAC_4K, S_SIP_FRAME, S_SIP_1K, S_SIP_4K, S_KEY_SETUP,
    S_VERIFY_STATUS, S_HMAC_OUT, S_SIP_OUT = S_HMAC_OUT + 8, S_WORDS = S_SIP_OUT + 2
};

__attribute__((section(".signature"))) volatile uint32_t sig[S_WORDS];

static uint8_t buf[4096];

static inline uint32_t mcycle(void)
{
    uint32_t v;
    __asm__ volatile("csrr %0, mcycle" : "=r"(v));
    return v;
}

int main(void)
{
    uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES] = {0}, key[TLP_AUTH_KEY_BYTES], out[TL_SHA256_BYTES];
    for (uint32_t i = 0; i < sizeof buf; i++)
        buf[i] = (uint8_t)(i * 7u + 3u);
    for (uint32_t i = 0; i < sizeof key; i++)
        key[i] = (uint8_t)i;
    /* the key slot as torqueloop.spec.auth.key_slot writes it */
    tl_put_u32(slot, TLP_AUTH_KEY_SLOT_MAGIC);
    tl_put_u32(&slot[4], TLP_AUTH_KEY_SLOT_ALGORITHM);
    for (uint32_t i = 0; i < sizeof key; i++)
        slot[8 + i] = key[i];
    tl_hmac_key_t hk;
    uint32_t t0 = mcycle();
    tl_hmac_key(&hk, key, sizeof key);
    sig[S_KEY_SETUP] = mcycle() - t0;
    tl_hmac(&hk, (const uint8_t *)TLP_AUTH_LABEL_CHECK, TLP_AUTH_LABEL_BYTES, out);
    for (uint32_t i = 0; i < 4u; i++)
        slot[8 + TLP_AUTH_KEY_BYTES + i] = out[i];

    static tl_auth_t a;
    tl_auth_init(&a, slot);
    uint8_t hn[TLP_AUTH_NONCE_BYTES] = {1, 2, 3}, bn[TLP_AUTH_NONCE_BYTES], proof[TLP_AUTH_TAG_BYTES];
    t0 = mcycle();
    (void)tl_auth_session(&a, hn, 12345u, bn, proof);
    sig[S_SESSION] = mcycle() - t0;

    tl_frame_t f = {.seq = 77, .cmd = TLP_CMD_SET_PARAM, .len = TLP_CMD_SET_PARAM_REQ_LEN + TLP_AUTH_TAG_BYTES,
                    .payload = {0, TLP_P_KP_Q16, 0x10, 0x27, 0, 0}};
    tl_auth_tag(&a, f.seq, f.cmd, f.payload, TLP_CMD_SET_PARAM_REQ_LEN, &f.payload[TLP_CMD_SET_PARAM_REQ_LEN]);
    t0 = mcycle();
    sig[S_VERIFY_STATUS] = tl_auth_verify(&a, &f);
    sig[S_VERIFY] = mcycle() - t0;

    uint8_t block[55];
    for (uint32_t i = 0; i < sizeof block; i++)
        block[i] = buf[i];
    t0 = mcycle();
    tl_sha256(block, sizeof block, out);
    sig[S_SHA_BLOCK] = mcycle() - t0;

    t0 = mcycle();
    tl_hmac(&hk, buf, 1024u, out);
    sig[S_HMAC_1K] = mcycle() - t0;
    for (uint32_t i = 0; i < 8u; i++)
        sig[S_HMAC_OUT + i] = tl_get_u32(&out[4 * i]);
    t0 = mcycle();
    tl_hmac(&hk, buf, 4096u, out);
    sig[S_HMAC_4K] = mcycle() - t0;

    /* SipHash over the message a frame MAC covers: label, two nonces, header, SET_PARAM payload */
    uint8_t msg[TLP_AUTH_LABEL_BYTES + 2u * TLP_AUTH_NONCE_BYTES + TLP_HEADER_BYTES + TLP_CMD_SET_PARAM_REQ_LEN];
    for (uint32_t i = 0; i < sizeof msg; i++)
        msg[i] = buf[i];
    volatile uint64_t sink;
    t0 = mcycle();
    sink = tl_siphash24(key, msg, sizeof msg);
    sig[S_SIP_FRAME] = mcycle() - t0;
    t0 = mcycle();
    uint64_t s1k = tl_siphash24(key, buf, 1024u);
    sig[S_SIP_1K] = mcycle() - t0;
    t0 = mcycle();
    sink = tl_siphash24(key, buf, 4096u);
    sig[S_SIP_4K] = mcycle() - t0;
    (void)sink;
    sig[S_SIP_OUT] = (uint32_t)s1k;
    sig[S_SIP_OUT + 1] = (uint32_t)(s1k >> 32);
    return sig[S_VERIFY_STATUS] == TLP_ST_OK ? 0 : 1;
}
