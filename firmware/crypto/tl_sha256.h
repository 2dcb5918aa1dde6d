/* SPDX-License-Identifier: MIT */
/* SHA-256 (FIPS 180-4) and HMAC-SHA-256 (RFC 2104), written for this
 * project: the MAC of the link's authenticated frames and of uploaded
 * firmware (docs/security.md).  Plain C11, no hardware access, no tables
 * beyond the 64 round constants, small stack (a 16-word rolling message
 * schedule): the same file runs in the servo firmware, in the boot ROM
 * bootloader, in the host tests and under the fuzzer.  Checked against
 * RFC 4231 and against Python's hashlib/hmac on random inputs
 * (tests/test_auth_crypto.py). */
#ifndef TL_SHA256_H
#define TL_SHA256_H

#include <stddef.h>
#include <stdint.h>

#define TL_SHA256_BYTES 32u
#define TL_SHA256_BLOCK 64u

typedef struct {
    uint32_t h[8];
    uint8_t buf[TL_SHA256_BLOCK];
    uint32_t fill;        /* bytes in buf */
    uint32_t blocks;      /* whole blocks compressed (messages < 256 GiB) */
} tl_sha256_t;

void tl_sha256_init(tl_sha256_t *c);
void tl_sha256_update(tl_sha256_t *c, const uint8_t *p, size_t n);
void tl_sha256_final(tl_sha256_t *c, uint8_t out[TL_SHA256_BYTES]);
void tl_sha256(const uint8_t *p, size_t n, uint8_t out[TL_SHA256_BYTES]);

/* A key made ready for HMAC: the chaining values after the key ^ ipad and
 * key ^ opad blocks, computed once, so each MAC costs the message's blocks
 * plus two compressions instead of four. */
typedef struct {
    uint32_t inner[8];
    uint32_t outer[8];
} tl_hmac_key_t;

typedef struct {
    tl_sha256_t c;
    const tl_hmac_key_t *k;
} tl_hmac_t;

void tl_hmac_key(tl_hmac_key_t *k, const uint8_t *key, size_t len);
void tl_hmac_init(tl_hmac_t *m, const tl_hmac_key_t *k);
void tl_hmac_update(tl_hmac_t *m, const uint8_t *p, size_t n);
void tl_hmac_final(tl_hmac_t *m, uint8_t out[TL_SHA256_BYTES]);
void tl_hmac(const tl_hmac_key_t *k, const uint8_t *p, size_t n, uint8_t out[TL_SHA256_BYTES]);

/* 1 if the n bytes are equal; the time does not depend on where they differ. */
int tl_ct_equal(const uint8_t *a, const uint8_t *b, size_t n);

#endif
