/* SPDX-License-Identifier: MIT */
/* A fake of hal.h for host tests and the fuzzer: the "hardware" is this struct. */
#ifndef TL_HAL_FAKE_H
#define TL_HAL_FAKE_H

#include "hal.h"
#include "tl_protocol.h"

typedef struct {
    tl_enc_sample_t enc[2];
    int32_t pwm_cmd[2];
    bool pwm_on[2];
    bool brake[2];
    uint32_t fdiv[2], pw0[2], pwmax[2];
    uint32_t safety;          /* TL_HAL_SAFE_* */
    uint32_t baud_div;
    uint32_t illegal_clears;
    bool limit_block[2];
    bool index_armed[2], index_seen[2];
    int32_t index_pos[2];
    uint32_t latch_after_read;   /* set these SYS latch bits right after the next hal_safety() read */
    int irq_depth;
    uint8_t key_slot[TLP_AUTH_KEY_SLOT_BYTES];   /* blank after reset: a board without a key */
    uint32_t cycles;
} hal_fake_t;

extern hal_fake_t hal_fake;
void hal_fake_reset(void);
/* Write key into the key slot as torqueloop.spec.auth.key_slot does (magic, algorithm, key, check). */
void hal_fake_set_key(const uint8_t key[TLP_AUTH_KEY_BYTES]);

#endif
