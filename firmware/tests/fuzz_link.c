/* SPDX-License-Identifier: MIT */
/* libFuzzer target: the servo's receive path (link layer, authentication,
 * command handler) on the fake HAL, with ASan/UBSan.  The board holds a key
 * and a session is open (as a host would have left it), axis 0 enabled.
 * The first input byte chooses who speaks:
 *
 *  - even: an attacker without the key.  The rest goes to the receive path
 *    as bytes.  Checked beyond memory safety: no authenticated frame is ever
 *    accepted (no MAC forged), no parameter changes, no axis gets enabled,
 *    no move runs (the target stays, or becomes the held position: STOP),
 *    no bootloader jump - stopping and disabling are all it may do - and
 *    every byte the firmware sends decodes as a valid frame.
 *  - odd: the key holder.  The rest is a list of frames
 *    [flags seq_lo seq_hi cmd len payload[len]] that this harness encodes,
 *    with the session's MAC appended if flags bit 0 (bit 1 flips one bit of
 *    it, bit 2 sends the frame twice, bit 3 opens a new session first), so
 *    the fuzzer reaches every command behind the MAC check and the session's
 *    replay rules.  Checked: a frame with a flipped MAC bit, sent a second
 *    time, or sent again later in the session (whatever untagged frames did
 *    to the link's seq in between) is never executed - but STOP and
 *    disabling, which run whatever their seq - and the critical sections
 *    balance.
 *
 * Build: clang -fsanitize=fuzzer,address,undefined (tests/test_firmware_host.py). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hal_fake.h"
#include "servo.h"

static tl_rx_t reply_rx;

static bool check_tx(const uint8_t *wire, uint32_t len)
{
    tl_frame_t f;
    uint8_t st;
    for (uint32_t i = 0; i < len; i++) {
        if (tl_rx_byte(&reply_rx, wire[i], &f, &st) == TL_RX_ERROR)
            abort();   /* the firmware sent a malformed frame */
    }
    if (len == 0u || wire[len - 1u] != 0u)
        abort();
    return true;
}

static const uint8_t KEY[TLP_AUTH_KEY_BYTES] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16,
                                                17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32};
static tl_servo_t s, before;
static tl_auth_t host;

static void open_session(void)
{
    uint8_t hn[TLP_AUTH_NONCE_BYTES] = {0xA5}, proof[TLP_AUTH_TAG_BYTES];
    host = s.auth;
    (void)tl_auth_session(&s.auth, hn, hal_cycles(), host.board_nonce, proof);
    memcpy(host.host_nonce, hn, sizeof hn);
}

static void feed(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        tl_servo_rx_byte(&s, p[i], check_tx);
}

static void key_holder(const uint8_t *data, size_t size)
{
    uint16_t seen[64];   /* seqs of the authenticated frames this session accepted */
    uint32_t n_seen = 0;
    size_t i = 0;
    while (i + 5u <= size) {
        uint8_t flags = data[i], cmd = data[i + 3], len = data[i + 4];
        uint16_t seq = (uint16_t)(data[i + 1] | data[i + 2] << 8);
        i += 5u;
        if (len > TLP_MAX_PAYLOAD - TLP_AUTH_TAG_BYTES || i + len > size)
            return;
        uint8_t p[TLP_MAX_PAYLOAD], wire[TLP_MAX_WIRE];
        memcpy(p, &data[i], len);
        i += len;
        if (flags & 8u) {
            open_session();
            n_seen = 0;
        }
        uint8_t n = len;
        if (flags & 1u) {
            tl_auth_tag(&host, seq, cmd, p, len, &p[len]);
            if (flags & 2u)
                p[len + (seq % TLP_AUTH_TAG_BYTES)] ^= (uint8_t)(1u << (cmd & 7u));
            n = (uint8_t)(len + TLP_AUTH_TAG_BYTES);
        }
        size_t wl = tl_frame_encode(seq, cmd, p, n, wire, sizeof wire);
        uint16_t ok = s.cnt.frames_ok;
        feed(wire, wl);
        if ((flags & 3u) == 3u && tlp_needs_key(cmd, p) && s.cnt.frames_ok != ok)
            abort();   /* a command that needs the key ran with a flipped MAC bit */
        /* STOP and disabling run whatever their seq (tl_auth_stopping): running them again is harmless */
        bool any_seq = cmd == TLP_CMD_IDENTIFY || cmd == TLP_CMD_SESSION || tl_auth_stopping(cmd, p);
        if ((flags & 3u) == 1u && s.cnt.frames_ok != ok && !any_seq) {
            for (uint32_t k = 0; k < n_seen; k++)
                if (seen[k] == seq)
                    abort();   /* an authenticated frame ran twice in one session */
            if (n_seen < 64u)
                seen[n_seen++] = seq;
        }
        if (flags & 4u) {
            ok = s.cnt.frames_ok;
            feed(wire, wl);
            /* the second copy is never executed (IDENTIFY, SESSION, STOP and disabling answer any seq,
               as specified) */
            if (s.cnt.frames_ok != ok && !any_seq)
                abort();
        }
        if (seq & 0x40u)
            tl_servo_tick(&s);   /* interleave control periods */
    }
}

static void attacker(const uint8_t *data, size_t size)
{
    for (size_t i = 0; i < size; i++) {
        tl_servo_rx_byte(&s, data[i], check_tx);
        if (data[i] == 0x40u)
            tl_servo_tick(&s);
    }
    int32_t t0 = (int32_t)(s.ax[0].c.target_q16 >> 16);
    if (s.auth.started ||                                            /* a MAC was forged */
        memcmp(s.ax[0].p, before.ax[0].p, sizeof s.ax[0].p) || memcmp(s.ax[1].p, before.ax[1].p, sizeof s.ax[1].p) ||
        memcmp(s.g, before.g, sizeof s.g) || s.ax[1].enabled || s.bootloader_req ||
        (s.ax[0].c.target_q16 != before.ax[0].c.target_q16 && t0 != s.ax[0].pos) ||
        hal_fake.pwm_on[1] || (hal_fake.pwm_on[0] && !s.ax[0].enabled) || hal_fake.fdiv[0] != before.ax[0].p[tl_param_index(TLP_P_FDIV)])
        abort();   /* someone without the key changed the machine */
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* The starting state is built once (the key's HMAC states cost eight
     * compressions) and copied for every input. */
    static bool ready;
    static tl_servo_t start;
    static tl_auth_t start_host;
    static hal_fake_t start_hw;
    if (!ready) {
        hal_fake_reset();
        hal_fake_set_key(KEY);
        hal_fake.enc[0].pos = 100;
        tl_servo_init(&s);
        open_session();
        /* an enabled axis 0 (as a host would have left it) */
        hal_fake.safety = 0;
        s.ax[0].enabled = true;
        hal_pwm_enable(0, true, true);
        start = s;
        start_host = host;
        start_hw = hal_fake;
        ready = true;
    }
    s = start;
    host = start_host;
    hal_fake = start_hw;
    before = s;
    tl_rx_init(&reply_rx);
    if (size && (data[0] & 1u))
        key_holder(data + 1, size - 1u);
    else if (size)
        attacker(data + 1, size - 1u);
    if (hal_fake.irq_depth != 0)
        abort();
    return 0;
}
