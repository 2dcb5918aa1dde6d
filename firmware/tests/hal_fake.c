/* SPDX-License-Identifier: MIT */
/* hal.h on the host: registers are fields of hal_fake (hal_fake.h). */
#include "hal_fake.h"

#include "tl_keyslot.h"
#include "tl_link.h"

hal_fake_t hal_fake;

void hal_fake_reset(void)
{
    hal_fake = (hal_fake_t){0};
    /* power-up: the SoC latch holds the drives safe with its reset-time ESTOP bit */
    hal_fake.safety = TL_HAL_SAFE_FORCED | TL_HAL_SAFE_ESTOP;
}

void hal_enc_read(uint32_t axis, tl_enc_sample_t *s) { *s = hal_fake.enc[axis]; }
void hal_enc_clear_illegal(uint32_t axis)
{
    hal_fake.enc[axis].illegal = 0;
    hal_fake.illegal_clears++;
}
void hal_enc_index_arm(uint32_t axis)
{
    hal_fake.index_armed[axis] = true;
    hal_fake.index_seen[axis] = false;
}
bool hal_enc_index(uint32_t axis, int32_t *pos)
{
    *pos = hal_fake.index_pos[axis];
    return hal_fake.index_seen[axis];
}
void hal_limit_block(uint32_t axis, bool on) { hal_fake.limit_block[axis] = on; }
void hal_pwm_cmd(uint32_t axis, int32_t cmd) { hal_fake.pwm_cmd[axis] = cmd; }
void hal_pwm_enable(uint32_t axis, bool on, bool brake)
{
    hal_fake.pwm_on[axis] = on;
    hal_fake.brake[axis] = brake;
}
void hal_pwm_config(uint32_t axis, uint32_t fdiv, uint32_t pw0, uint32_t pwmax)
{
    hal_fake.fdiv[axis] = fdiv;
    hal_fake.pw0[axis] = pw0;
    hal_fake.pwmax[axis] = pwmax;
}
uint32_t hal_safety(void)
{
    uint32_t v = hal_fake.safety;
    /* a cause latching between the firmware's read and its acknowledgement */
    if (hal_fake.latch_after_read) {
        hal_fake.safety |= hal_fake.latch_after_read | TL_HAL_SAFE_FORCED;
        hal_fake.latch_after_read = 0;
    }
    return v;
}
void hal_safety_ack(uint32_t bits)
{
    /* W1C; a cause still present (e-stop input, bridge fault input) keeps its bit, as in soc_sys */
    uint32_t keep = (hal_fake.safety & TL_HAL_SAFE_ESTOP_IN) ? TL_HAL_SAFE_ESTOP : 0u;
    if (hal_fake.enc[0].bridge_fault)
        keep |= TL_HAL_SAFE_FAULT0;
    if (hal_fake.enc[1].bridge_fault)
        keep |= TL_HAL_SAFE_FAULT1;
    hal_fake.safety &= ~(bits & ~keep);
    if (!(hal_fake.safety & (TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG |
                             TL_HAL_SAFE_ESTOP_IN)))
        hal_fake.safety &= ~TL_HAL_SAFE_FORCED;
}
uint32_t hal_build_id(void) { return 0x1234ABCDu; }
uint32_t hal_clk_hz(void) { return 50000000u; }
const uint8_t *hal_key_slot(void) { return hal_fake.key_slot; }
uint32_t hal_cycles(void) { return hal_fake.cycles += 37u; }

void hal_fake_set_key(const uint8_t key[TLP_AUTH_KEY_BYTES])
{
    uint8_t *s = hal_fake.key_slot, mac[TL_SHA256_BYTES];
    tl_put_u32(s, TLP_AUTH_KEY_SLOT_MAGIC);
    tl_put_u32(&s[4], TLP_AUTH_KEY_SLOT_ALGORITHM);
    for (uint32_t i = 0; i < TLP_AUTH_KEY_BYTES; i++)
        s[TL_KEYSLOT_KEY_OFS + i] = key[i];
    tl_hmac_key_t k;
    tl_hmac_key(&k, key, TLP_AUTH_KEY_BYTES);
    tl_hmac(&k, (const uint8_t *)TLP_AUTH_LABEL_CHECK, TLP_AUTH_LABEL_BYTES, mac);
    for (uint32_t i = 0; i < TL_KEYSLOT_CHECK_BYTES; i++)
        s[TL_KEYSLOT_CHECK_OFS + i] = mac[i];
}
void hal_set_baud_div(uint32_t div) { hal_fake.baud_div = div; }
void hal_irq_off(void) { hal_fake.irq_depth++; }
void hal_irq_on(void) { hal_fake.irq_depth--; }
/* No configuration flash on the fake board: reads float high (erased, no stored
 * parameters) and a write never sets the enable latch (SAVE answers STORE). */
void hal_flash_select(bool on) { (void)on; }
uint8_t hal_flash_xfer(uint8_t out)
{
    (void)out;
    return 0xFFu;
}
