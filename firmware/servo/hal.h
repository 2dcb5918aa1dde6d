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
    uint8_t limits;         /* limit switches open now (synchronised, debounced): TL_HAL_LIM_* */
} tl_enc_sample_t;

#define TL_HAL_LIM_NEG 0x01u        /* negative-end switch open (tripped or wire broken) */
#define TL_HAL_LIM_POS 0x02u

/* SoC safety latch bits as the servo core sees them (a subset of SYS.SAFETY). */
#define TL_HAL_SAFE_FORCED 0x01u    /* drives forced safe now */
#define TL_HAL_SAFE_ESTOP_IN 0x02u  /* e-stop input present now */
#define TL_HAL_SAFE_ESTOP 0x04u     /* latched: e-stop */
#define TL_HAL_SAFE_FAULT0 0x08u
#define TL_HAL_SAFE_FAULT1 0x10u
#define TL_HAL_SAFE_WDOG 0x20u

void hal_enc_clear_illegal(uint32_t axis);
/* Encoder index latch: arm it, then poll; true once an index pulse latched *pos (encoder counts). */
void hal_enc_index_arm(uint32_t axis);
bool hal_enc_index(uint32_t axis, int32_t *pos);
/* Hardware limit block: while on, the bridge side that drives toward an open
 * limit switch is held off in the SoC (LIMIT_SW = 1); off for an axis without switches. */
void hal_limit_block(uint32_t axis, bool on);
void hal_pwm_enable(uint32_t axis, bool on, bool brake);
void hal_pwm_config(uint32_t axis, uint32_t fdiv, uint32_t pw0, uint32_t pwmax);
/* Write-one-to-clear the latched cause bits (TL_HAL_SAFE_ESTOP/FAULTn/WDOG). */
void hal_safety_ack(uint32_t bits);
uint32_t hal_build_id(void);
uint32_t hal_clk_hz(void);
/* The boot ROM's key slot (TLP_AUTH_KEY_SLOT_BYTES, docs/security.md). */
const uint8_t *hal_key_slot(void);
/* A free-running cycle counter: entropy for the session challenge (tl_auth.h). */
uint32_t hal_cycles(void);
void hal_set_baud_div(uint32_t div);
void hal_irq_off(void);
void hal_irq_on(void);
/* The configuration flash's serial port (the SoC's FLASH page, the ASMI block on
 * the DE0-CV): chip select, and one byte out and one in, MSB first (SPI mode 0). */
void hal_flash_select(bool on);
uint8_t hal_flash_xfer(uint8_t out);

/* The control iteration's accessors: inline on the SoC (hal_soc_inline.h; the iteration
 * reads the decoder with hal_enc_read_inline, every other caller with the function),
 * functions elsewhere. */
void hal_enc_read(uint32_t axis, tl_enc_sample_t *s);
#ifdef TL_HAL_SOC_INLINE
#include "hal_soc_inline.h"
#else
#define hal_enc_read_inline hal_enc_read
void hal_pwm_cmd(uint32_t axis, int32_t cmd);
uint32_t hal_safety(void);
#endif

#endif
