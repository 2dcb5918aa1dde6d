/* SPDX-License-Identifier: MIT */
/* hal.h on the torqueloop SoC: every address from the generated register header. */
#include "hal.h"

#include "tl_protocol.h"
#include "torqueloop_regs.h"

/* hal_pwm_cmd and hal_safety: static inline in hal_soc_inline.h (AX there too). */

void hal_enc_read(uint32_t axis, tl_enc_sample_t *s) { hal_enc_read_inline(axis, s); }


/* PWM_CTRL.LIMIT_EN as hal_limit_block set it, kept in every PWM_CTRL write. */
static uint32_t limit_en[2] = {TL_AXIS_PWM_CTRL_LIMIT_EN_MSK, TL_AXIS_PWM_CTRL_LIMIT_EN_MSK};

void hal_enc_clear_illegal(uint32_t axis) { AX(axis, ENC_CMD) = TL_AXIS_ENC_CMD_ILLEGAL_CLEAR_MSK; }

void hal_enc_index_arm(uint32_t axis) { AX(axis, ENC_CMD) = TL_AXIS_ENC_CMD_INDEX_ARM_MSK; }

bool hal_enc_index(uint32_t axis, int32_t *pos)
{
    if (!(AX(axis, ENC_STATUS) & TL_AXIS_ENC_STATUS_INDEX_SEEN_MSK))
        return false;
    *pos = (int32_t)AX(axis, ENC_INDEX_POS);
    return true;
}

void hal_limit_block(uint32_t axis, bool on)
{
    limit_en[axis] = on ? TL_AXIS_PWM_CTRL_LIMIT_EN_MSK : 0u;
    uint32_t ctrl = AX(axis, PWM_CTRL);
    AX(axis, PWM_CTRL) = (ctrl & ~TL_AXIS_PWM_CTRL_LIMIT_EN_MSK) | limit_en[axis];
}


void hal_pwm_enable(uint32_t axis, bool on, bool brake)
{
    AX(axis, PWM_CTRL) = (on ? TL_AXIS_PWM_CTRL_ENABLE_MSK : 0u) | (brake ? TL_AXIS_PWM_CTRL_BRAKE_MSK : 0u) |
                         limit_en[axis];
}

void hal_pwm_config(uint32_t axis, uint32_t fdiv, uint32_t pw0, uint32_t pwmax)
{
    AX(axis, FDIV) = fdiv & TL_AXIS_FDIV_DIV_MSK;
    AX(axis, PWM_PW0) = pw0 & TL_AXIS_PWM_PW0_PW0_MSK;
    AX(axis, PWM_PWMAX) = pwmax & TL_AXIS_PWM_PWMAX_PWMAX_MSK;
}


void hal_safety_ack(uint32_t bits)
{
    uint32_t w = 0;
    if (bits & TL_HAL_SAFE_ESTOP) w |= TL_SYS_SAFETY_ESTOP_MSK;
    if (bits & TL_HAL_SAFE_FAULT0) w |= TL_SYS_SAFETY_FAULT0_MSK;
    if (bits & TL_HAL_SAFE_FAULT1) w |= TL_SYS_SAFETY_FAULT1_MSK;
    if (bits & TL_HAL_SAFE_WDOG) w |= TL_SYS_SAFETY_WDOG_MSK;
    TL_SYS_SAFETY = w;
}

uint32_t hal_build_id(void) { return TL_SYS_BUILD_ID; }

const uint8_t *hal_key_slot(void)
{
    /* The last bytes of the boot ROM, copied a word at a time (the ROM is read as words). */
    static uint32_t slot[TLP_AUTH_KEY_SLOT_BYTES / 4u];
    const volatile uint32_t *rom =
        (const volatile uint32_t *)(uintptr_t)(TL_BOOT_ROM_BASE + TL_BOOT_ROM_SIZE - TLP_AUTH_KEY_SLOT_BYTES);
    for (uint32_t i = 0; i < TLP_AUTH_KEY_SLOT_BYTES / 4u; i++)
        slot[i] = rom[i];
    return (const uint8_t *)slot;
}

uint32_t hal_cycles(void)
{
    uint32_t v;
    __asm__ volatile("csrr %0, mcycle" : "=r"(v));
    return v;
}
uint32_t hal_clk_hz(void) { return TL_SYS_CLK_HZ; }
void hal_set_baud_div(uint32_t div) { TL_UART_BAUD_DIV = div & TL_UART_BAUD_DIV_DIV_MSK; }
void hal_irq_off(void) { __asm__ volatile("csrc mstatus, %0" : : "r"(1u << 3) : "memory"); }
void hal_irq_on(void) { __asm__ volatile("csrs mstatus, %0" : : "r"(1u << 3) : "memory"); }

/* The FLASH page (regmap.toml): chip select, and a byte clocked out and in. */
void hal_flash_select(bool on) { TL_FLASH_CTRL = on ? TL_FLASH_CTRL_CS_MSK : 0u; }
uint8_t hal_flash_xfer(uint8_t out)
{
    TL_FLASH_TX = out;
    uint32_t rx;
    while ((rx = TL_FLASH_RX) & TL_FLASH_RX_BUSY_MSK) {
    }
    return (uint8_t)(rx & TL_FLASH_RX_DATA_MSK);
}
