/* SPDX-License-Identifier: MIT */
/* SipHash-2-4 (Aumasson and Bernstein, "SipHash: a fast short-input PRF",
 * INDOCRYPT 2012), written for this project as the measured alternative to
 * HMAC-SHA-256 for the link MAC (docs/security.md, "Why HMAC-SHA-256"): the
 * protocol does not use it; scripts/benches/bench_auth.py measures both on
 * the RTL.  Checked against the reference implementation's 64 vectors and
 * against torqueloop.spec.auth.siphash24 on random inputs. */
#ifndef TL_SIPHASH_H
#define TL_SIPHASH_H

#include <stddef.h>
#include <stdint.h>

#define TL_SIPHASH_KEY_BYTES 16u

/* The 64-bit tag of n bytes under a 16-byte key (k0 = key[0..7], k1 =
 * key[8..15], little-endian); the tag's bytes are its little-endian form. */
uint64_t tl_siphash24(const uint8_t key[TL_SIPHASH_KEY_BYTES], const uint8_t *p, size_t n);

#endif
