/* SPDX-License-Identifier: MIT */
/* SHA-256 and HMAC-SHA-256 (tl_sha256.h). */
#include "tl_sha256.h"

static const uint32_t K[64] = {
    0x428a2f98u, 0x71374491u, 0xb5c0fbcfu, 0xe9b5dba5u, 0x3956c25bu, 0x59f111f1u, 0x923f82a4u, 0xab1c5ed5u,
    0xd807aa98u, 0x12835b01u, 0x243185beu, 0x550c7dc3u, 0x72be5d74u, 0x80deb1feu, 0x9bdc06a7u, 0xc19bf174u,
    0xe49b69c1u, 0xefbe4786u, 0x0fc19dc6u, 0x240ca1ccu, 0x2de92c6fu, 0x4a7484aau, 0x5cb0a9dcu, 0x76f988dau,
    0x983e5152u, 0xa831c66du, 0xb00327c8u, 0xbf597fc7u, 0xc6e00bf3u, 0xd5a79147u, 0x06ca6351u, 0x14292967u,
    0x27b70a85u, 0x2e1b2138u, 0x4d2c6dfcu, 0x53380d13u, 0x650a7354u, 0x766a0abbu, 0x81c2c92eu, 0x92722c85u,
    0xa2bfe8a1u, 0xa81a664bu, 0xc24b8b70u, 0xc76c51a3u, 0xd192e819u, 0xd6990624u, 0xf40e3585u, 0x106aa070u,
    0x19a4c116u, 0x1e376c08u, 0x2748774cu, 0x34b0bcb5u, 0x391c0cb3u, 0x4ed8aa4au, 0x5b9cca4fu, 0x682e6ff3u,
    0x748f82eeu, 0x78a5636fu, 0x84c87814u, 0x8cc70208u, 0x90befffau, 0xa4506cebu, 0xbef9a3f7u, 0xc67178f2u,
};

static const uint32_t H0[8] = {
    0x6a09e667u, 0xbb67ae85u, 0x3c6ef372u, 0xa54ff53au, 0x510e527fu, 0x9b05688cu, 0x1f83d9abu, 0x5be0cd19u,
};

static inline uint32_t ror(uint32_t x, unsigned n) { return (x >> n) | (x << (32u - n)); }

static void compress(uint32_t h[8], const uint8_t *blk)
{
    uint32_t w[16];
    for (unsigned i = 0; i < 16u; i++)
        w[i] = (uint32_t)blk[4 * i] << 24 | (uint32_t)blk[4 * i + 1] << 16 | (uint32_t)blk[4 * i + 2] << 8 |
               blk[4 * i + 3];
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (unsigned i = 0; i < 64u; i++) {
        if (i >= 16u) {
            /* W[i] = s1(W[i-2]) + W[i-7] + s0(W[i-15]) + W[i-16], in a ring of 16 */
            uint32_t x = w[(i + 1u) & 15u], y = w[(i + 14u) & 15u];
            w[i & 15u] += (ror(x, 7) ^ ror(x, 18) ^ (x >> 3)) + (ror(y, 17) ^ ror(y, 19) ^ (y >> 10)) +
                          w[(i + 9u) & 15u];
        }
        uint32_t t1 = hh + (ror(e, 6) ^ ror(e, 11) ^ ror(e, 25)) + ((e & f) ^ (~e & g)) + K[i] + w[i & 15u];
        uint32_t t2 = (ror(a, 2) ^ ror(a, 13) ^ ror(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        hh = g;
        g = f;
        f = e;
        e = d + t1;
        d = c;
        c = b;
        b = a;
        a = t1 + t2;
    }
    h[0] += a;
    h[1] += b;
    h[2] += c;
    h[3] += d;
    h[4] += e;
    h[5] += f;
    h[6] += g;
    h[7] += hh;
}

static void h0(uint32_t h[8])
{
    for (unsigned i = 0; i < 8u; i++)
        h[i] = H0[i];
}

void tl_sha256_init(tl_sha256_t *c)
{
    h0(c->h);
    c->fill = 0;
    c->blocks = 0;
}

void tl_sha256_update(tl_sha256_t *c, const uint8_t *p, size_t n)
{
    while (n) {
        if (c->fill == 0u && n >= TL_SHA256_BLOCK) {
            compress(c->h, p);      /* whole blocks straight from the input */
            c->blocks++;
            p += TL_SHA256_BLOCK;
            n -= TL_SHA256_BLOCK;
            continue;
        }
        c->buf[c->fill++] = *p++;
        n--;
        if (c->fill == TL_SHA256_BLOCK) {
            compress(c->h, c->buf);
            c->blocks++;
            c->fill = 0;
        }
    }
}

static void put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

void tl_sha256_final(tl_sha256_t *c, uint8_t out[TL_SHA256_BYTES])
{
    uint32_t fill = c->fill;
    /* message length in bits, as a 64-bit big-endian number */
    uint32_t bits_lo = (c->blocks << 9) + (fill << 3), bits_hi = c->blocks >> 23;
    c->buf[fill++] = 0x80u;
    if (fill > TL_SHA256_BLOCK - 8u) {
        while (fill < TL_SHA256_BLOCK)
            c->buf[fill++] = 0u;
        compress(c->h, c->buf);
        fill = 0;
    }
    while (fill < TL_SHA256_BLOCK - 8u)
        c->buf[fill++] = 0u;
    put_be32(&c->buf[56], bits_hi);
    put_be32(&c->buf[60], bits_lo);
    compress(c->h, c->buf);
    for (unsigned i = 0; i < 8u; i++)
        put_be32(&out[4 * i], c->h[i]);
}

void tl_sha256(const uint8_t *p, size_t n, uint8_t out[TL_SHA256_BYTES])
{
    tl_sha256_t c;
    tl_sha256_init(&c);
    tl_sha256_update(&c, p, n);
    tl_sha256_final(&c, out);
}

void tl_hmac_key(tl_hmac_key_t *k, const uint8_t *key, size_t len)
{
    uint8_t pad[TL_SHA256_BLOCK] = {0};
    if (len > TL_SHA256_BLOCK) {
        tl_sha256(key, len, pad);         /* RFC 2104: a long key is hashed first */
    } else {
        for (size_t i = 0; i < len; i++)
            pad[i] = key[i];
    }
    for (unsigned i = 0; i < TL_SHA256_BLOCK; i++)
        pad[i] ^= 0x36u;                  /* ipad */
    h0(k->inner);
    compress(k->inner, pad);
    for (unsigned i = 0; i < TL_SHA256_BLOCK; i++)
        pad[i] ^= 0x36u ^ 0x5Cu;          /* ipad -> opad */
    h0(k->outer);
    compress(k->outer, pad);
}

void tl_hmac_init(tl_hmac_t *m, const tl_hmac_key_t *k)
{
    for (unsigned i = 0; i < 8u; i++)
        m->c.h[i] = k->inner[i];
    m->c.fill = 0;
    m->c.blocks = 1;      /* the key block */
    m->k = k;
}

void tl_hmac_update(tl_hmac_t *m, const uint8_t *p, size_t n) { tl_sha256_update(&m->c, p, n); }

void tl_hmac_final(tl_hmac_t *m, uint8_t out[TL_SHA256_BYTES])
{
    uint8_t inner[TL_SHA256_BYTES];
    tl_sha256_final(&m->c, inner);
    for (unsigned i = 0; i < 8u; i++)
        m->c.h[i] = m->k->outer[i];
    m->c.fill = 0;
    m->c.blocks = 1;
    tl_sha256_update(&m->c, inner, sizeof inner);
    tl_sha256_final(&m->c, out);
}

void tl_hmac(const tl_hmac_key_t *k, const uint8_t *p, size_t n, uint8_t out[TL_SHA256_BYTES])
{
    tl_hmac_t m;
    tl_hmac_init(&m, k);
    tl_hmac_update(&m, p, n);
    tl_hmac_final(&m, out);
}

int tl_ct_equal(const uint8_t *a, const uint8_t *b, size_t n)
{
    uint8_t d = 0;
    for (size_t i = 0; i < n; i++)
        d |= (uint8_t)(a[i] ^ b[i]);
    return d == 0u;
}
