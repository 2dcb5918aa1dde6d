/* SPDX-License-Identifier: MIT */
/* The link protocol's commands (docs/protocol.md).  Every command is a row of
 * the table generated from protocol.toml (TLP_COMMAND_TABLE in tl_protocol.h:
 * code, handler, request and reply length, flags) and one cmd_* function here;
 * dispatch() admits a frame by its row and calls the function.
 *  - A command that changes the machine runs only with a MAC of the open
 *    session (tl_auth.h, docs/security.md); reading, STOP and disabling need none;
 *  - a frame that fails any check, or a replayed one, is counted and answered
 *    with an error and changes nothing;
 *  - only commands that show the host in control (TLP_CF_FEEDS_LINK), executed
 *    with a verified MAC, feed the link watchdog. */
#include "servo_internal.h"
#include "store.h"

/* A handler: q the request payload, rep the reply payload (rep[0], the status,
 * is written by dispatch); returns the status.  On TLP_ST_OK the reply is the
 * row's reply length; a refusal puts the rule into *why (TLP_WHY_*), and the
 * reply is the status and the rule.  Compiled for size
 * (TL_FOR_SIZE) but MOVE, whose critical section is its own; the other
 * critical sections live in params.c, safety.c and homing.c, at -O2. */
typedef uint8_t (*cmd_fn)(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why);

typedef struct {
    cmd_fn fn;
    uint8_t req_len;
    uint8_t rep_len;
    uint8_t flags;   /* TLP_CF_* */
} cmd_row_t;

#define TL_CMD_DECLARE(code, fn, req_len, rep_len, flags) \
    static uint8_t fn(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why);
TLP_COMMAND_TABLE(TL_CMD_DECLARE)
#define TL_CMD_ROW(code, fn, req_len, rep_len, flags) [code] = {fn, req_len, rep_len, flags},
static const cmd_row_t COMMANDS[TLP_CMD_LIMIT] = {TLP_COMMAND_TABLE(TL_CMD_ROW)};

static void sat_inc(uint16_t *c)
{
    if (*c != 0xFFFFu)
        (*c)++;
}

/* ---- the commands ------------------------------------------------------- */

TL_FOR_SIZE static uint8_t cmd_identify(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)why;
    (void)q;
    rep[TLP_IDENTIFY_REP_PROTO_VERSION] = TLP_VERSION;
    tl_put_u16(&rep[TLP_IDENTIFY_REP_FW_VERSION], TLP_FIRMWARE_VERSION);
    tl_put_u32(&rep[TLP_IDENTIFY_REP_BUILD_ID], hal_build_id());
    rep[TLP_IDENTIFY_REP_AXIS_COUNT] = TL_AXES;
    tl_put_u16(&rep[TLP_IDENTIFY_REP_LAST_SEQ], s->seq.last);
    tl_put_u32(&rep[TLP_IDENTIFY_REP_CLK_HZ], s->clk_hz);
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_get_param(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    int32_t v = 0;
    uint8_t st = tl_param_get(s, q[TLP_GET_PARAM_REQ_AXIS], q[TLP_GET_PARAM_REQ_PARAM], &v, why);
    tl_put_u32(&rep[TLP_GET_PARAM_REP_VALUE], (uint32_t)v);
    return st;
}

/* The reply echoes the value stored (a physical gain reads back through its raw gain). */
TL_FOR_SIZE static uint8_t cmd_set_param(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    uint8_t axis = q[TLP_SET_PARAM_REQ_AXIS], id = q[TLP_SET_PARAM_REQ_PARAM];
    uint8_t st = tl_param_set(s, axis, id, (int32_t)tl_get_u32(&q[TLP_SET_PARAM_REQ_VALUE]), why);
    int32_t v = 0;
    if (st == TLP_ST_OK)
        (void)tl_param_get(s, axis, id, &v, why);
    tl_put_u32(&rep[TLP_SET_PARAM_REP_VALUE], (uint32_t)v);
    return st;
}

TL_FOR_SIZE static uint8_t cmd_enable(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    uint8_t mask = q[TLP_ENABLE_REQ_MASK], on = q[TLP_ENABLE_REQ_ENABLE];
    if (!axis_mask_ok(mask))
        return refuse(why, TLP_WHY_AXIS);
    if (on > 1u)
        return refuse(why, TLP_WHY_CHOICE);
    if (!on) {
        tl_axes_disable(s, mask);
        return TLP_ST_OK;
    }
    return tl_axes_enable(s, mask, why);
}

static uint8_t cmd_move(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    uint8_t axis = q[TLP_MOVE_REQ_AXIS], mode = q[TLP_MOVE_REQ_MODE];
    int32_t target = (int32_t)tl_get_u32(&q[TLP_MOVE_REQ_TARGET]);
    if (axis >= TL_AXES)
        return refuse(why, TLP_WHY_AXIS);
    if (mode & (uint8_t)~(TLP_MOVE_TRAPEZOID | TLP_MOVE_UNHOMED))
        return refuse(why, TLP_WHY_CHOICE);
    tl_axis_t *a = &s->ax[axis];
    if (!a->enabled)
        return refuse(why, TLP_WHY_DISABLED);
    if (a->home == TLP_HOME_STATE_HOMING)
        return refuse(why, TLP_WHY_HOMING);
    if (a->home != TLP_HOME_STATE_HOMED && !(mode & TLP_MOVE_UNHOMED))
        return refuse(why, TLP_WHY_NOT_HOMED);
    if (target < pv(a, TLP_P_SOFT_MIN) || target > pv(a, TLP_P_SOFT_MAX))
        return refuse(why, TLP_WHY_OUTSIDE_SOFT);
    uint8_t b = tl_blocked(a);
    if (((b & TLP_LIMIT_NEG) && target < a->pos) || ((b & TLP_LIMIT_POS) && target > a->pos))
        return refuse(why, TLP_WHY_LIMIT);
    int64_t d = (int64_t)target - a->pos;
    if (!(mode & TLP_MOVE_TRAPEZOID) && (d > pv(a, TLP_P_FOLLOW_LIMIT) || -d > pv(a, TLP_P_FOLLOW_LIMIT)))
        return refuse(why, TLP_WHY_FOLLOW);   /* the following error would trip at once */
    hal_irq_off();
    a->drive = false;
    tl_ctl_move(&a->c, target, (mode & TLP_MOVE_TRAPEZOID) != 0u);
    hal_irq_on();
    return TLP_ST_OK;
}

/* Hold where they are (profile or homing abandoned); the axes stay enabled. */
TL_FOR_SIZE static uint8_t cmd_stop(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    uint8_t m = q[TLP_STOP_REQ_MASK];
    if (!axis_mask_ok(m))
        return refuse(why, TLP_WHY_AXIS);
    hal_irq_off();
    for (uint32_t i = 0; i < TL_AXES; i++)
        if (m & (1u << i)) {
            if (s->ax[i].home == TLP_HOME_STATE_HOMING)
                s->ax[i].home = TLP_HOME_STATE_NOT_HOMED;
            s->ax[i].drive = false;
            tl_ctl_hold(&s->ax[i].c, s->ax[i].pos);
        }
    hal_irq_on();
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_status(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    uint8_t axis = q[TLP_STATUS_REQ_AXIS];
    if (axis >= TL_AXES)
        return refuse(why, TLP_WHY_AXIS);
    const tl_axis_t *a = &s->ax[axis];
    rep[TLP_STATUS_REP_ENABLED] = a->enabled;
    tl_put_u16(&rep[TLP_STATUS_REP_FAULTS], a->faults);
    rep[TLP_STATUS_REP_MOVING] = a->c.moving || a->home == TLP_HOME_STATE_HOMING;
    rep[TLP_STATUS_REP_HOME] = a->home;
    rep[TLP_STATUS_REP_LIMITS] = a->limits;
    tl_put_u32(&rep[TLP_STATUS_REP_POSITION], (uint32_t)a->pos);
    tl_put_u32(&rep[TLP_STATUS_REP_SETPOINT], (uint32_t)(int32_t)(a->c.sp_q16 >> 16));
    tl_put_u32(&rep[TLP_STATUS_REP_VELOCITY_Q8], (uint32_t)a->c.vel_q8);
    tl_put_u16(&rep[TLP_STATUS_REP_PWM_CMD], (uint16_t)(int16_t)a->cmd);
    tl_put_u16(&rep[TLP_STATUS_REP_SAFETY], (uint16_t)hal_safety());
    uint32_t errs = (uint32_t)s->cnt.crc + s->cnt.framing + s->cnt.length + s->cnt.oversize;
    tl_put_u16(&rep[TLP_STATUS_REP_RX_ERRORS], (uint16_t)(errs > 0xFFFFu ? 0xFFFFu : errs));
    tl_put_u32(&rep[TLP_STATUS_REP_LOOP_CYCLES_MAX], s->loop_cycles_max);
    tl_put_u32(&rep[TLP_STATUS_REP_JITTER_CYCLES_MAX], s->jitter_cycles_max);
    tl_put_u32(&rep[TLP_STATUS_REP_OVERRUNS], s->overruns);
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_telemetry(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)why;
    (void)rep;
    hal_irq_off();
    uint32_t every = tl_get_u16(&q[TLP_TELEMETRY_REQ_EVERY]), ticks = s->ticks;
    s->telem_every = every;
    s->telem_next = every ? ticks - ticks % every + every : 0u;   /* records at the multiples of every */
    hal_irq_on();
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_clear_fault(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    uint8_t mask = q[TLP_CLEAR_FAULT_REQ_MASK];
    if (!axis_mask_ok(mask))
        return refuse(why, TLP_WHY_AXIS);
    uint8_t st = tl_axes_clear(s, mask, why);
    tl_put_u16(&rep[TLP_CLEAR_FAULT_REP_FAULTS0], s->ax[0].faults);
    tl_put_u16(&rep[TLP_CLEAR_FAULT_REP_FAULTS1], s->ax[1].faults);
    return st;
}

/* Both drives off; main.c jumps to the boot ROM once the reply is out. */
TL_FOR_SIZE static uint8_t cmd_bootloader(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    if (tl_get_u32(&q[TLP_BOOTLOADER_REQ_MAGIC]) != TLP_BOOTLOADER_MAGIC)
        return refuse(why, TLP_WHY_CHOICE);
    tl_axes_disable(s, (uint8_t)((1u << TL_AXES) - 1u));
    s->bootloader_req = true;
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_counters(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)why;
    (void)q;
    const uint16_t vals[10] = {s->cnt.frames_ok, s->cnt.crc, s->cnt.framing, s->cnt.length, s->cnt.oversize,
                               s->cnt.unknown, s->cnt.replay, s->cnt.rejected, s->cnt.tx_dropped, s->cnt.auth};
    for (uint32_t k = 0; k < 10u; k++)
        tl_put_u16(&rep[TLP_COUNTERS_REP_FRAMES_OK + 2u * k], vals[k]);
    return TLP_ST_OK;
}

/* Nothing but feeding the link watchdog (dispatch does that). */
TL_FOR_SIZE static uint8_t cmd_heartbeat(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)s, (void)q, (void)rep, (void)why;
    return TLP_ST_OK;
}

TL_FOR_SIZE static uint8_t cmd_home(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    return tl_home_start(s, q[TLP_HOME_REQ_AXIS], q[TLP_HOME_REQ_MODE], q[TLP_HOME_REQ_INDEX], why);
}

TL_FOR_SIZE static uint8_t cmd_drive(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)rep;
    return tl_drive_start(s, q[TLP_DRIVE_REQ_AXIS], (int16_t)tl_get_u16(&q[TLP_DRIVE_REQ_DUTY]), why);
}

TL_FOR_SIZE static uint8_t cmd_save(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    return tl_store_command(s, q[TLP_SAVE_REQ_OP], rep, why);
}

TL_FOR_SIZE static uint8_t cmd_session(tl_servo_t *s, const uint8_t *q, uint8_t *rep, uint8_t *why)
{
    (void)why;   /* NO_KEY says it all */
    return tl_auth_session(&s->auth, &q[TLP_SESSION_REQ_HOST_NONCE], hal_cycles(), &rep[TLP_SESSION_REP_BOARD_NONCE],
                           &rep[TLP_SESSION_REP_PROOF]);
}

/* ---- frames in, replies out --------------------------------------------- */

TL_FOR_SIZE static void send(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, const uint8_t *p, uint8_t len)
{
    uint8_t wire[TLP_MAX_WIRE];
    uint32_t n = (uint32_t)tl_frame_encode(seq, cmd, p, len, wire, sizeof wire);
    if (n == 0u || !tx(wire, n))
        sat_inc(&s->cnt.tx_dropped);
}

TL_FOR_SIZE static void send_status(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, uint8_t st)
{
    send(s, tx, seq, cmd, &st, 1u);
}

/* The checks before a command runs, in order: its length (with or without a
 * MAC), the key it needs, a new seq (for a sequence-checked command), the MAC;
 * each refusal counted.  *tagged: a MAC came with it and verified with a new
 * seq (what shows the host in control).  STOP and disabling run whatever their
 * seq and MAC (tl_auth_stopping): injected frames cannot block a stop. */
TL_FOR_SIZE static uint8_t admit(tl_servo_t *s, const tl_frame_t *f, const cmd_row_t *c, bool *tagged)
{
    *tagged = f->len == c->req_len + TLP_AUTH_TAG_BYTES;   /* a MAC follows the payload */
    if (!*tagged && f->len != c->req_len) {
        sat_inc(&s->cnt.length);
        return TLP_ST_LENGTH;
    }
    if (!*tagged && tlp_needs_key(f->cmd, f->payload)) {
        sat_inc(&s->cnt.auth);
        return tl_auth_missing(&s->auth);
    }
    bool checked = (c->flags & TLP_CF_SEQ_CHECKED) != 0u;
    bool fresh = !checked || tl_seq_is_new(&s->seq, f->seq);
    bool stopping = tl_auth_stopping(f->cmd, f->payload);
    if (!fresh && !stopping) {
        sat_inc(&s->cnt.replay);
        return TLP_ST_REPLAY;
    }
    if (*tagged && fresh) {
        uint8_t ast = tl_auth_verify(&s->auth, f);   /* outside the control interrupt: ~29 000 cycles */
        if (ast != TLP_ST_OK && !stopping) {
            sat_inc(ast == TLP_ST_REPLAY ? &s->cnt.replay : &s->cnt.auth);
            return ast;
        }
        *tagged = ast == TLP_ST_OK;   /* a stop all the same, but it shows no one in control */
    } else {
        *tagged = false;
    }
    if (checked && fresh)
        tl_seq_accept(&s->seq, f->seq);
    sat_inc(&s->cnt.frames_ok);
    return TLP_ST_OK;
}

TL_FOR_SIZE static void dispatch(tl_servo_t *s, const tl_frame_t *f, tl_tx_fn tx)
{
    uint8_t rc = f->cmd | TLP_REPLY_FLAG;
    const cmd_row_t *c = f->cmd < TLP_CMD_LIMIT ? &COMMANDS[f->cmd] : 0;
    if (c == 0 || c->fn == 0) {
        sat_inc(&s->cnt.unknown);
        send_status(s, tx, f->seq, rc, TLP_ST_UNKNOWN_CMD);
        return;
    }
    bool tagged;
    uint8_t st = admit(s, f, c, &tagged);
    if (st != TLP_ST_OK) {
        send_status(s, tx, f->seq, rc, st);
        return;
    }
    uint8_t rep[TLP_MAX_PAYLOAD];
    uint8_t why = TLP_WHY_NONE;
    st = c->fn(s, f->payload, rep, &why);
    uint8_t n = c->rep_len;
    if (st != TLP_ST_OK) {
        sat_inc(&s->cnt.rejected);
        rep[TLP_REPLY_WHY] = why;
        n = TLP_REPLY_WHY + 1u;
    } else if (tagged && (c->flags & TLP_CF_FEEDS_LINK)) {
        /* The host is in control: only a command that carried a verified MAC
         * feeds the watchdog (read-only commands never do, nor a STOP sent
         * without the key, which would otherwise keep an axis enabled for
         * anyone on the network). */
        s->link_idle_ticks = 0;
    }
    rep[0] = st;
    send(s, tx, f->seq, rc, rep, n);
}

TL_FOR_SIZE void tl_servo_rx_byte(tl_servo_t *s, uint8_t byte, tl_tx_fn tx)
{
    tl_frame_t f;
    uint8_t st = 0;
    tl_auth_stir(&s->auth, hal_cycles());
    switch (tl_rx_byte(&s->rx, byte, &f, &st)) {
    case TL_RX_FRAME:
        dispatch(s, &f, tx);
        break;
    case TL_RX_ERROR:
        switch (st) {
        case TLP_ST_CRC: sat_inc(&s->cnt.crc); break;
        case TLP_ST_LENGTH: sat_inc(&s->cnt.length); break;
        case TLP_ST_OVERSIZE: sat_inc(&s->cnt.oversize); break;
        default: sat_inc(&s->cnt.framing); break;
        }
        send_status(s, tx, 0u, TLP_ERROR_CMD, st);
        break;
    default:
        break;
    }
}
