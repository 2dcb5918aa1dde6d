/* SPDX-License-Identifier: MIT */
/* What the servo core needs from the hardware.  servo/hal_soc.c implements
 * it on the torqueloop SoC registers; firmware/tests/hal_fake.c on the host. */
#ifndef TL_HAL_H
#define TL_HAL_H

#include <stdbool.h>
#include <stdint.h>

typedef struct {
    int32_t pos;            /* encoder counts */
    uint32_t edge_time;     /* decoder clock cycles of the last count */
    uint32_t now;           /* decoder clock now */
    uint32_t interval;      /* decoder clock cycles between the last two counts */
    uint32_t illegal;       /* illegal-transition count */
    bool bridge_fault;      /* bridge fault input now */
} tl_enc_sample_t;

/* SoC safety latch bits as the servo core sees them (a subset of SYS.SAFETY). */
#define TL_HAL_SAFE_FORCED 0x01u    /* drives forced safe now */
#define TL_HAL_SAFE_ESTOP_IN 0x02u  /* e-stop input present now */
#define TL_HAL_SAFE_ESTOP 0x04u     /* latched: e-stop */
#define TL_HAL_SAFE_FAULT0 0x08u
#define TL_HAL_SAFE_FAULT1 0x10u
#define TL_HAL_SAFE_WDOG 0x20u

void hal_enc_read(uint32_t axis, tl_enc_sample_t *s);
void hal_enc_clear_illegal(uint32_t axis);
void hal_pwm_cmd(uint32_t axis, int32_t cmd);
void hal_pwm_enable(uint32_t axis, bool on, bool brake);
void hal_pwm_config(uint32_t axis, uint32_t fdiv, uint32_t pw0, uint32_t pwmax);
uint32_t hal_safety(void);
/* Write-one-to-clear the latched cause bits (TL_HAL_SAFE_ESTOP/FAULTn/WDOG). */
void hal_safety_ack(uint32_t bits);
uint32_t hal_build_id(void);
uint32_t hal_clk_hz(void);
void hal_set_baud_div(uint32_t div);
void hal_irq_off(void);
void hal_irq_on(void);

#endif
