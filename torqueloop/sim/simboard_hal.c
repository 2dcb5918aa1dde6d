/* SPDX-License-Identifier: MIT */
/* The servo firmware on the host, for the simulated board of `torqueloop sim`
 * (torqueloop/sim/simboard.py).  servo.c, tl_link.c and control.c run
 * unchanged; this file is their hal.h (the "registers" are the statics
 * below, read and written from Python through ctypes) and the main loop of
 * firmware/servo/main.c without the RISC-V parts: bytes in, one control
 * iteration per period, telemetry frames out.  Compiled to a shared library
 * by simboard.py into build/host/. */
#include <string.h>

#include "hal.h"
#include "servo.h"
#include "tl_link.h"

static tl_servo_t servo;
static tl_enc_sample_t enc[2];
static int32_t pwm_cmd[2];
static int32_t pwm_on[2], pwm_brake[2], limit_block[2];
static int32_t index_armed[2], index_seen[2], index_pos[2];
static uint32_t pwm_fdiv[2], pwm_pw0[2], pwm_pwmax[2];
static uint32_t safety;
static uint32_t baud_div;
static uint32_t build_id;
static uint8_t key_slot[TLP_AUTH_KEY_SLOT_BYTES];   /* the boot ROM's last bytes (sb_reset) */
static uint32_t cycles;                             /* mcycle: the simulated clock, running (sb_set_clock) */
static uint8_t tx_buf[16384];
static uint32_t tx_len;

/* ---- hal.h --------------------------------------------------------------- */
void hal_enc_read(uint32_t axis, tl_enc_sample_t *s) { *s = enc[axis]; }
void hal_enc_clear_illegal(uint32_t axis) { enc[axis].illegal = 0; }
void hal_enc_index_arm(uint32_t axis)
{
    index_armed[axis] = 1;
    index_seen[axis] = 0;
}
bool hal_enc_index(uint32_t axis, int32_t *pos)
{
    *pos = index_pos[axis];
    return index_seen[axis] != 0;
}
void hal_limit_block(uint32_t axis, bool on) { limit_block[axis] = on; }
void hal_pwm_cmd(uint32_t axis, int32_t cmd) { pwm_cmd[axis] = cmd; }
void hal_pwm_enable(uint32_t axis, bool on, bool brake)
{
    pwm_on[axis] = on;
    pwm_brake[axis] = brake;
}
void hal_pwm_config(uint32_t axis, uint32_t fdiv, uint32_t pw0, uint32_t pwmax)
{
    pwm_fdiv[axis] = fdiv;
    pwm_pw0[axis] = pw0;
    pwm_pwmax[axis] = pwmax;
}
uint32_t hal_safety(void) { return safety; }
void hal_safety_ack(uint32_t bits)
{
    /* W1C like soc_sys: a cause still present (e-stop input) keeps its bit. */
    uint32_t keep = (safety & TL_HAL_SAFE_ESTOP_IN) ? TL_HAL_SAFE_ESTOP : 0u;
    if (enc[0].bridge_fault)
        keep |= TL_HAL_SAFE_FAULT0;
    if (enc[1].bridge_fault)
        keep |= TL_HAL_SAFE_FAULT1;
    safety &= ~(bits & ~keep);
    if (!(safety & (TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG |
                    TL_HAL_SAFE_ESTOP_IN)))
        safety &= ~TL_HAL_SAFE_FORCED;
}
uint32_t hal_build_id(void) { return build_id; }
uint32_t hal_clk_hz(void) { return 50000000u; }
const uint8_t *hal_key_slot(void) { return key_slot; }
uint32_t hal_cycles(void) { return cycles; }
void hal_set_baud_div(uint32_t div) { baud_div = div; }
void hal_irq_off(void) {}
void hal_irq_on(void) {}

/* The configuration flash: the EPCS model of torqueloop/sim/epcs.py behind two
 * callbacks (sb_set_flash).  A byte takes 8 serial clocks at a quarter of the
 * system clock, as the SoC's FLASH port would clock it; the firmware's flash
 * timeouts count hal_cycles, so the time spent here counts there too. */
#define FLASH_BYTE_CYCLES 32u
typedef void (*sb_flash_select_fn)(int32_t on);
typedef uint32_t (*sb_flash_xfer_fn)(uint32_t out);
static sb_flash_select_fn flash_select_cb;
static sb_flash_xfer_fn flash_xfer_cb;
void sb_set_flash(sb_flash_select_fn sel, sb_flash_xfer_fn xfer)
{
    flash_select_cb = sel;
    flash_xfer_cb = xfer;
}
void hal_flash_select(bool on)
{
    if (flash_select_cb)
        flash_select_cb(on);
}
uint8_t hal_flash_xfer(uint8_t out)
{
    cycles += FLASH_BYTE_CYCLES;
    return flash_xfer_cb ? (uint8_t)flash_xfer_cb(out) : 0xFFu;
}

static bool tx(const uint8_t *wire, uint32_t len)
{
    if (tx_len + len > sizeof tx_buf)
        return false;
    memcpy(&tx_buf[tx_len], wire, len);
    tx_len += len;
    return true;
}

/* ---- the simulator's side -------------------------------------------------- */
/* Power-up with the encoders as sb_set_encoder left them (the plant's rest
 * position) and a boot ROM whose key slot holds these bytes. */
void sb_reset(uint32_t id, const uint8_t *slot)
{
    memcpy(key_slot, slot, sizeof key_slot);
    memset(pwm_cmd, 0, sizeof pwm_cmd);
    memset(pwm_on, 0, sizeof pwm_on);
    memset(pwm_brake, 0, sizeof pwm_brake);
    memset(limit_block, 0, sizeof limit_block);
    memset(index_armed, 0, sizeof index_armed);
    memset(index_seen, 0, sizeof index_seen);
    /* power-up: the SoC latch holds the drives safe with its reset-time ESTOP bit */
    safety = TL_HAL_SAFE_FORCED | TL_HAL_SAFE_ESTOP;
    baud_div = 0;
    build_id = id;
    tx_len = 0;
    /* crt0 clears .bss at every firmware start: nothing of the last run's
     * state (the nonce generator's stir, pool and count) survives a restart */
    memset(&servo, 0, sizeof servo);
    tl_servo_init(&servo);
}

/* The bytes of one write arrive now, one UART character (10 bits of
 * BAUD_DIV + 1 clocks) after the other, so the cycle counter the firmware
 * reads at each runs on as on the board. */
void sb_rx(uint32_t now, const uint8_t *data, uint32_t len)
{
    uint32_t char_cycles = 10u * (baud_div + 1u);
    for (uint32_t i = 0; i < len; i++) {
        cycles = now + (i + 1u) * char_cycles;
        tl_servo_rx_byte(&servo, data[i], tx);
    }
}

/* One control period: the timer interrupt, then what main.c's loop does next. */
void sb_tick(void)
{
    tl_servo_tick(&servo);
    tl_servo_stream_telemetry(&servo, tx);
    if (servo.baud_div_pending) {
        baud_div = servo.baud_div_pending;
        servo.baud_div_pending = 0;
    }
}

uint32_t sb_tx_take(uint8_t *dst, uint32_t cap)
{
    uint32_t n = tx_len < cap ? tx_len : cap;
    memcpy(dst, tx_buf, n);
    memmove(tx_buf, &tx_buf[n], tx_len - n);
    tx_len -= n;
    return n;
}

void sb_set_encoder(uint32_t axis, int32_t pos, uint32_t edge_time, uint32_t interval, uint32_t now,
                    uint32_t illegal, int32_t bridge_fault, uint32_t limits)
{
    enc[axis].limits = (uint8_t)limits;
    enc[axis].pos = pos;
    enc[axis].edge_time = edge_time;
    enc[axis].interval = interval;
    enc[axis].now = now;
    cycles = now;   /* the control interrupt's moment */
    enc[axis].illegal = illegal;
    enc[axis].bridge_fault = bridge_fault != 0;
    if (bridge_fault)   /* soc_sys latches the bridge fault input and forces the drives safe */
        safety |= (axis ? TL_HAL_SAFE_FAULT1 : TL_HAL_SAFE_FAULT0) | TL_HAL_SAFE_FORCED;
}

/* The decoder's index latch: armed by the firmware, latched by the simulator at a Z rise. */
int32_t sb_index_armed(uint32_t axis) { return index_armed[axis] && !index_seen[axis]; }
void sb_index_latch(uint32_t axis, int32_t pos)
{
    index_pos[axis] = pos;
    index_seen[axis] = 1;
}

/* Whether the firmware takes its speed from the decoder's edge timestamps
 * (VEL_MODE 1): simboard.py then steps the plant's last edges of a period. */
int32_t sb_vel_mode(uint32_t axis) { return (int32_t)servo.ax[axis].ctl.vel_mode; }

/* drive[0..6] = cmd, on, brake, fdiv, pw0, pwmax, limit block */
void sb_get_drive(uint32_t axis, int32_t *drive)
{
    drive[6] = limit_block[axis];
    drive[0] = pwm_cmd[axis];
    drive[1] = pwm_on[axis];
    drive[2] = pwm_brake[axis];
    drive[3] = (int32_t)pwm_fdiv[axis];
    drive[4] = (int32_t)pwm_pw0[axis];
    drive[5] = (int32_t)pwm_pwmax[axis];
}

/* The e-stop input (KEY0): pressed sets the input and latches ESTOP, forcing the drives safe. */
void sb_set_estop(int32_t pressed)
{
    if (pressed)
        safety |= TL_HAL_SAFE_ESTOP_IN | TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FORCED;
    else
        safety &= ~TL_HAL_SAFE_ESTOP_IN;
}

uint32_t sb_period_us(void) { return (uint32_t)servo.g[tl_param_index(TLP_P_PERIOD_US)]; }
uint32_t sb_baud_div(void) { return baud_div; }
int32_t sb_bootloader_requested(void) { return servo.bootloader_req; }
