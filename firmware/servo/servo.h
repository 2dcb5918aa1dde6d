/* SPDX-License-Identifier: MIT */
/* The servo application without its hardware: parameters, two axes under
 * control.c, the safety state machine and the command handler of the link
 * protocol (servo_internal.h says which file holds what).  servo/main.c calls
 * tl_servo_tick() from the machine-timer interrupt and feeds received bytes to
 * tl_servo_rx_byte(); everything else goes through hal.h, so the host tests,
 * the fuzzer and the simulated board run this very code. */
#ifndef TL_SERVO_H
#define TL_SERVO_H

#include <stdbool.h>
#include <stdint.h>

#include "control.h"
#include "tl_auth.h"
#include "tl_link.h"

#define TL_AXES TLP_AXIS_COUNT   /* the protocol's axis count (torqueloop/spec/system.toml) */

/* Encoder plausibility constants (enc_check.h), derived from the parameters. */
typedef struct {
    int32_t k_q8;                 /* half the model's speed per command step above ENC_CMD0, counts/s q8 */
    int32_t alpha_q16;            /* that time / ENC_TAU_MS, q16, at most 1 */
    int32_t dt_q16;               /* the time between two checks (tl_runaway_every periods), s q16 */
} tl_enc_cfg_t;

typedef struct {
    int32_t p[TLP_PARAM_COUNT];   /* raw parameter values, indexed like TLP_PARAM_INFO */
    tl_ctl_params_t ctl;          /* control view of the same values */
    tl_ctl_t c;
    bool enabled;
    uint16_t faults;              /* TLP_FAULT_* latched */
    uint32_t illegal_seen;
    int32_t pos;                  /* encoder count + offset, counts (absolute once homed) */
    int32_t offset;               /* set by homing */
    int32_t cmd;                  /* PWM command applied since the last tick (direction blocks included) */
    uint8_t limits;               /* TLP_LIMIT_* switches open at the last tick (0 with LIMIT_SW = 0) */
    uint8_t limit_mask;           /* derived: both TLP_LIMIT_* bits with LIMIT_SW, else 0 */
    uint8_t recover;              /* TLP_LIMIT_* soft-limit side the axis was enabled outside of */
    uint8_t home;                 /* TLP_HOME_STATE_* */
    uint8_t home_phase;
    int8_t home_dir;              /* toward the switch: -1 negative end, +1 positive end */
    bool home_index;              /* go on to the encoder index after the switch */
    int64_t home_sp_q16;          /* homing set-point, counts q16 */
    int8_t stall_dir;             /* runaway check: sign of a command >= STALL_CMD, 0 none */
    int32_t stall_ref;            /* position the axis must pass in stall_dir */
    int32_t stall_vel_q8;         /* velocity (counts/s q8) it must exceed in stall_dir */
    uint32_t stall_ticks;         /* runaway checks without passing it */
    uint32_t stall_limit_ticks;   /* derived: STALL_MS in runaway checks (one every tl_runaway_every periods) */
    int64_t home_step_q16;        /* derived: HOME_VEL per period, counts q16 */
    int8_t enc_dir;               /* encoder plausibility: sign of a command above ENC_CMD0, 0 none */
    int32_t enc_ref;              /* position at the last period */
    int32_t enc_vlo_q8;           /* lower bound of the speed in enc_dir, counts/s q8 */
    int64_t enc_exp_q24;          /* counts the encoder is behind that speed's distance, q24 */
    tl_enc_cfg_t enc;             /* derived */
    bool drive;                   /* open-loop drive (DRIVE, openloop.c): the command is drive_duty */
    int16_t drive_duty;           /* signed PWM steps, |duty| <= CMD_LIMIT */
} tl_axis_t;

typedef struct {
    uint16_t frames_ok, crc, framing, length, oversize, unknown, replay, rejected, tx_dropped, auth;
} tl_counters_t;

typedef struct {
    tl_axis_t ax[TL_AXES];
    int32_t g[TLP_PARAM_COUNT];   /* global parameters, same indexing */
    tl_rx_t rx;
    tl_seq_t seq;
    tl_auth_t auth;               /* the key and the session (tl_auth.h) */
    tl_counters_t cnt;
    uint32_t ticks;               /* control periods since start */
    uint32_t link_idle_ticks;     /* control periods since the last valid command */
    uint32_t telem_every;         /* TELEMETRY's u16, periods between records (0: off) */
    uint32_t telem_next;          /* the period count the next record is due at (a multiple of telem_every) */
    uint16_t telem_seq;
    bool bootloader_req;
    uint32_t baud_div_pending;    /* set the UART divisor once the reply is out (0 = none) */
    uint32_t loop_cycles_max;     /* worst control iteration (set by main.c) */
    uint32_t jitter_cycles_max;   /* worst lateness of the interrupt (set by main.c) */
    uint32_t overruns;            /* control periods whose next deadline had passed when the iteration ended (main.c) */
    uint32_t clk_hz;
    uint32_t period_cycles;       /* derived: PERIOD_US in clock cycles */
    uint32_t link_timeout_ticks;  /* derived: LINK_TIMEOUT_MS in control periods */
    uint32_t runaway_odd;         /* derived: tl_runaway_every(PERIOD_US) - 1 (1: an axis's runaway checks skip every other period) */
} tl_servo_t;

/* Transmit hook: a complete wire frame (delimiter included).  Returns false if dropped. */
typedef bool (*tl_tx_fn)(const uint8_t *wire, uint32_t len);

void tl_servo_init(tl_servo_t *s);
void tl_servo_tick(tl_servo_t *s);
void tl_servo_rx_byte(tl_servo_t *s, uint8_t byte, tl_tx_fn tx);
/* Is a telemetry record due (the main loop's, not the interrupt's: the period count
 * has reached telem_next)?  True once per due record; the next is due at the next
 * multiple of telem_every, a record the loop was too late for is skipped. */
bool tl_servo_telemetry_due(tl_servo_t *s);
/* The main loop's telemetry: when a record is due, the last tick's values (taken with the
 * interrupt off) framed and handed to tx; a record tx refuses is counted (tx_dropped). */
void tl_servo_stream_telemetry(tl_servo_t *s, tl_tx_fn tx);
/* Build the telemetry payload (TLP_TELEM_LEN bytes) from the last tick. */
void tl_servo_telemetry(const tl_servo_t *s, uint8_t *payload);
uint32_t tl_servo_period_cycles(const tl_servo_t *s);
int tl_param_index(uint8_t id);
/* The range [min, max] of the parameter at index k of TLP_PARAM_INFO (servo.c holds the table). */
void tl_param_range(uint32_t k, int32_t *lo, int32_t *hi);
/* DRIVE (openloop.c): put an enabled axis under the open-loop command duty; a TLP_ST_* status,
 * the refusal's rule (TLP_WHY_*) in *why. */
uint8_t tl_drive_start(tl_servo_t *s, uint8_t axis, int32_t duty, uint8_t *why);

#endif
