/* SPDX-License-Identifier: MIT */
/* Authenticated sessions of the link (docs/security.md): the board's key,
 * the SESSION challenge and the check of a command's MAC.  Plain C11 with
 * no hardware access (the key slot's bytes and the cycle counter come from
 * the caller), so the servo firmware, the host tests, the simulated board
 * and the fuzzer run this very code.  Nothing here runs in the control
 * interrupt: servo.c calls it from the receive path of the main loop.
 *
 *   SESSION(host_nonce): board_nonce = HMAC(key, "TLNG" | pool | count |
 *       cycles | stir | host_nonce)[:16], the whole 32 bytes the next pool;
 *       proof = HMAC(key, "TLSP" | host_nonce | board_nonce)[:16].  Ends any
 *       earlier session.
 *   a frame's MAC: HMAC(key, "TLCF" | board_nonce | host_nonce | seq cmd len
 *       | payload)[:16], appended to the payload (len counts it).
 *   replay: within a session the authenticated seqs, as offsets from the
 *       first one, only grow and stay below TLP_AUTH_SESSION_WINDOW - a
 *       count no other frame can move, so no recorded authenticated frame
 *       is ever accepted twice, whatever unauthenticated frames do to the
 *       link's own seq. */
#ifndef TL_AUTH_H
#define TL_AUTH_H

#include <stdbool.h>
#include <stdint.h>

#include "tl_link.h"
#include "tl_protocol.h"
#include "tl_sha256.h"

typedef struct {
    bool have_key;
    tl_hmac_key_t key;                            /* the key, ready for HMAC */
    bool open;                                    /* a session is open */
    bool started;                                 /* it has accepted an authenticated frame */
    uint16_t base;                                /* seq of that first frame */
    uint16_t last_off;                            /* offset of the newest one from base */
    uint8_t host_nonce[TLP_AUTH_NONCE_BYTES];
    uint8_t board_nonce[TLP_AUTH_NONCE_BYTES];
    uint8_t pool[TL_SHA256_BYTES];                /* the generator's hidden state */
    uint32_t count;                               /* sessions opened since power-up */
    uint32_t stir;                                /* the cycle counts of every byte received, folded */
} tl_auth_t;

/* The key from a boot-ROM key slot (TLP_AUTH_KEY_SLOT_BYTES): magic,
 * algorithm, key and its check value must all be right, or the board has
 * no key.  No session is open afterwards. */
void tl_auth_init(tl_auth_t *a, const uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES]);
/* Fold the cycle counter at a received byte into the generator (cheap). */
static inline void tl_auth_stir(tl_auth_t *a, uint32_t cycles) { a->stir = a->stir * 0x9E3779B1u + cycles; }
/* SESSION: TLP_ST_OK with the board's nonce and proof, or TLP_ST_NO_KEY. */
uint8_t tl_auth_session(tl_auth_t *a, const uint8_t host_nonce[TLP_AUTH_NONCE_BYTES], uint32_t cycles,
                        uint8_t board_nonce[TLP_AUTH_NONCE_BYTES], uint8_t proof[TLP_AUTH_TAG_BYTES]);
/* A command that shows the host in control yet needs no key can only take
 * motion away: STOP and disabling.  It runs whatever its seq (and whatever
 * its MAC), so frames injected into the link cannot block a stop; only a
 * fresh one with a verified MAC feeds the link watchdog
 * (torqueloop/spec/auth.py, stopping). */
static inline bool tl_auth_stopping(uint8_t cmd, const uint8_t *payload)
{
    uint8_t flags = 0;
    switch (cmd) {
#define TL_AUTH_FLAGS(code, handler, req_len, rep_len, f) \
    case code: flags = (uint8_t)(f); break;
        TLP_COMMAND_TABLE(TL_AUTH_FLAGS)
#undef TL_AUTH_FLAGS
    default: break;
    }
    return (flags & TLP_CF_FEEDS_LINK) != 0u && !tlp_needs_key(cmd, payload);
}
/* Status for a command that needs the key but came without a MAC. */
static inline uint8_t tl_auth_missing(const tl_auth_t *a) { return a->have_key ? TLP_ST_AUTH : TLP_ST_NO_KEY; }
/* A frame whose payload ends with a MAC: TLP_ST_OK (and the session moves on
 * to its seq), or NO_KEY, NO_SESSION, REPLAY, AUTH with nothing changed. */
uint8_t tl_auth_verify(tl_auth_t *a, const tl_frame_t *f);
/* The MAC of a frame in this session (the host's side; tests and the fuzzer). */
void tl_auth_tag(const tl_auth_t *a, uint16_t seq, uint8_t cmd, const uint8_t *payload, uint8_t payload_len,
                 uint8_t tag[TLP_AUTH_TAG_BYTES]);

#endif
