/* SPDX-License-Identifier: MIT */
/* SipHash-2-4 (tl_siphash.h): two compression rounds per 8-byte word, four
 * finalisation rounds. */
#include "tl_siphash.h"

static inline uint64_t rotl(uint64_t x, unsigned n) { return (x << n) | (x >> (64u - n)); }

static inline uint64_t le64(const uint8_t *p)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < 8u; i++)
        v |= (uint64_t)p[i] << (8u * i);
    return v;
}

#define SIPROUND                                                                                     \
    do {                                                                                             \
        v0 += v1;                                                                                    \
        v1 = rotl(v1, 13);                                                                           \
        v1 ^= v0;                                                                                    \
        v0 = rotl(v0, 32);                                                                           \
        v2 += v3;                                                                                    \
        v3 = rotl(v3, 16);                                                                           \
        v3 ^= v2;                                                                                    \
        v0 += v3;                                                                                    \
        v3 = rotl(v3, 21);                                                                           \
        v3 ^= v0;                                                                                    \
        v2 += v1;                                                                                    \
        v1 = rotl(v1, 17);                                                                           \
        v1 ^= v2;                                                                                    \
        v2 = rotl(v2, 32);                                                                           \
    } while (0)

uint64_t tl_siphash24(const uint8_t key[TL_SIPHASH_KEY_BYTES], const uint8_t *p, size_t n)
{
    uint64_t k0 = le64(key), k1 = le64(key + 8);
    uint64_t v0 = k0 ^ 0x736f6d6570736575ull, v1 = k1 ^ 0x646f72616e646f6dull;
    uint64_t v2 = k0 ^ 0x6c7967656e657261ull, v3 = k1 ^ 0x7465646279746573ull;
    size_t whole = n & ~(size_t)7u;
    for (size_t i = 0; i < whole; i += 8u) {
        uint64_t m = le64(p + i);
        v3 ^= m;
        SIPROUND;
        SIPROUND;
        v0 ^= m;
    }
    /* last word: the remaining bytes, and the length's low byte on top */
    uint64_t b = (uint64_t)(n & 0xFFu) << 56;
    for (size_t i = 0; i < (n & 7u); i++)
        b |= (uint64_t)p[whole + i] << (8u * i);
    v3 ^= b;
    SIPROUND;
    SIPROUND;
    v0 ^= b;
    v2 ^= 0xFFu;
    SIPROUND;
    SIPROUND;
    SIPROUND;
    SIPROUND;
    return v0 ^ v1 ^ v2 ^ v3;
}
