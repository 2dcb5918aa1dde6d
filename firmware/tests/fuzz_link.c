/* SPDX-License-Identifier: MIT */
/* libFuzzer target: arbitrary bytes into the servo's receive path (link
 * layer + command handler) on the fake HAL, with ASan/UBSan.  Beyond memory
 * safety it checks the protocol's promise: unless a frame was accepted
 * (frames_ok grew), no parameter, enable, set-point or PWM output changed,
 * and every byte the firmware sends decodes as a valid frame.
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
    for (uint32_t i = 0; i < len; i++)
        if (tl_rx_byte(&reply_rx, wire[i], &f, &st) == TL_RX_ERROR)
            abort();   /* the firmware sent a malformed frame */
    if (len == 0u || wire[len - 1u] != 0u)
        abort();
    return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static tl_servo_t s, before;
    hal_fake_reset();
    hal_fake.enc[0].pos = 100;
    tl_servo_init(&s);
    tl_rx_init(&reply_rx);
    /* start from an enabled axis 0 (as a host would have left it) */
    hal_fake.safety = 0;
    s.ax[0].enabled = true;
    hal_pwm_enable(0, true, true);
    memcpy(&before, &s, sizeof s);
    hal_fake_t hw = hal_fake;
    for (size_t i = 0; i < size; i++) {
        uint16_t ok = s.cnt.frames_ok;
        tl_servo_rx_byte(&s, data[i], check_tx);
        if (data[i] == 0x40u)
            tl_servo_tick(&s);   /* interleave control periods */
        if (s.cnt.frames_ok != ok)
            return 0;            /* a valid command: it may change things (the unit tests cover those) */
    }
    if (memcmp(s.ax[0].p, before.ax[0].p, sizeof s.ax[0].p) || memcmp(s.ax[1].p, before.ax[1].p, sizeof s.ax[1].p) ||
        memcmp(s.g, before.g, sizeof s.g) || s.ax[0].c.target_q16 != before.ax[0].c.target_q16 ||
        s.ax[1].enabled || hal_fake.pwm_on[1] != hw.pwm_on[1] || hal_fake.fdiv[0] != hw.fdiv[0] ||
        hal_fake.irq_depth != 0)
        abort();   /* noise changed the machine */
    return 0;
}
