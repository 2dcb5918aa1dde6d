/* SPDX-License-Identifier: MIT */
/* The firmware's cryptography on the host, line by line, for
 * tests/test_auth_crypto.py to compare with published vectors, Python's
 * hashlib/hmac and torqueloop/spec/auth.py (hex in, hex out; "-" is empty):
 *
 *   S msg                 SHA-256
 *   H key msg             HMAC-SHA-256 (any key length)
 *   I key msg             the same, fed to tl_hmac_update one byte at a time
 *   P key16 msg           SipHash-2-4 (the tag's little-endian bytes)
 *   K slot                tl_auth_init from a key slot -> have_key
 *   N host_nonce cycles stir      tl_auth_session -> status board_nonce proof pool
 *   T seq cmd payload     tl_auth_tag in the open session
 *   V seq cmd payload     tl_auth_verify of a frame whose payload ends with its tag -> status */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tl_auth.h"
#include "tl_sha256.h"
#include "tl_siphash.h"

static size_t unhex(const char *s, uint8_t *out, size_t cap)
{
    if (strcmp(s, "-") == 0)
        return 0;
    size_t n = strlen(s) / 2;
    if (n > cap || strlen(s) % 2) {
        fprintf(stderr, "bad hex\n");
        exit(2);
    }
    for (size_t i = 0; i < n; i++) {
        unsigned v;
        if (sscanf(&s[2 * i], "%2x", &v) != 1) {
            fprintf(stderr, "bad hex\n");
            exit(2);
        }
        out[i] = (uint8_t)v;
    }
    return n;
}

static void hex(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        printf("%02x", p[i]);
}

static char a1[70000], a2[70000], a3[70000];
static uint8_t b1[35000], b2[35000];

int main(void)
{
    static char line[3 * 70000];
    tl_auth_t auth;
    memset(&auth, 0, sizeof auth);
    while (fgets(line, sizeof line, stdin)) {
        char op = line[0];
        int n = sscanf(line + 1, "%69999s %69999s %69999s", a1, a2, a3);
        uint8_t out[TL_SHA256_BYTES];
        switch (op) {
        case 'S': {
            size_t m = unhex(a1, b1, sizeof b1);
            tl_sha256(b1, m, out);
            hex(out, sizeof out);
            break;
        }
        case 'H':
        case 'I': {
            size_t kl = unhex(a1, b1, sizeof b1), m = unhex(a2, b2, sizeof b2);
            tl_hmac_key_t k;
            tl_hmac_key(&k, b1, kl);
            if (op == 'H') {
                tl_hmac(&k, b2, m, out);
            } else {
                tl_hmac_t h;
                tl_hmac_init(&h, &k);
                for (size_t i = 0; i < m; i++)
                    tl_hmac_update(&h, &b2[i], 1);
                tl_hmac_final(&h, out);
            }
            hex(out, sizeof out);
            break;
        }
        case 'P': {
            (void)unhex(a1, b1, 16);
            size_t m = unhex(a2, b2, sizeof b2);
            uint64_t t = tl_siphash24(b1, b2, m);
            for (int i = 0; i < 8; i++)
                printf("%02x", (unsigned)(t >> (8 * i)) & 0xFFu);
            break;
        }
        case 'K': {
            uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES] = {0};
            (void)unhex(a1, slot, sizeof slot);
            tl_auth_init(&auth, slot);
            printf("%d", auth.have_key ? 1 : 0);
            break;
        }
        case 'N': {
            uint8_t hn[TLP_AUTH_NONCE_BYTES], bn[TLP_AUTH_NONCE_BYTES], proof[TLP_AUTH_TAG_BYTES];
            (void)unhex(a1, hn, sizeof hn);
            auth.stir = (uint32_t)strtoul(a3, NULL, 0);
            uint8_t st = tl_auth_session(&auth, hn, (uint32_t)strtoul(a2, NULL, 0), bn, proof);
            printf("%u ", st);
            hex(bn, sizeof bn);
            printf(" ");
            hex(proof, sizeof proof);
            printf(" ");
            hex(auth.pool, sizeof auth.pool);
            break;
        }
        case 'T':
        case 'V': {
            tl_frame_t f;
            f.seq = (uint16_t)strtoul(a1, NULL, 0);
            f.cmd = (uint8_t)strtoul(a2, NULL, 0);
            f.len = (uint8_t)unhex(n >= 3 ? a3 : "-", f.payload, sizeof f.payload);
            if (op == 'T') {
                uint8_t tag[TLP_AUTH_TAG_BYTES];
                tl_auth_tag(&auth, f.seq, f.cmd, f.payload, f.len, tag);
                hex(tag, sizeof tag);
            } else {
                printf("%u", tl_auth_verify(&auth, &f));
            }
            break;
        }
        default:
            continue;
        }
        printf("\n");
        fflush(stdout);
    }
    return 0;
}
