/* SPDX-License-Identifier: MIT */
/* Host unit tests of the firmware's plain C: link layer, control law,
 * trapezoid profile, the servo core's safety and command handling and its
 * authentication (on the fake HAL).  Run by tests/test_firmware_host.py.
 *
 *   host_tests unit [seed]   run every test; prints the seed and the counts
 *   host_tests ctl           line-driven control.c and enc_check.h, compared
 *                            with torqueloop/oracles/servo.py by the Python test */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "control.h"
#include "enc_check.h"
#include "hal_fake.h"
#include "servo.h"
#include "tl_link.h"

static unsigned checks, failures;
#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        checks++;                                                                \
        if (!(cond)) {                                                           \
            failures++;                                                          \
            fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                        \
            fputc('\n', stderr);                                                 \
        }                                                                        \
    } while (0)

static uint64_t rng_state;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state >> 11);
}

/* ---- link ---------------------------------------------------------------- */

static void test_link(void)
{
    const uint8_t check_str[] = "123456789";
    CHECK(tl_crc16(check_str, 9, 0xFFFFu) == 0x29B1u, "CRC-16/CCITT-FALSE check value");
    for (int n = 0; n < 2000; n++) {
        uint8_t a[300], enc[310], dec[300];
        size_t len = rnd() % 300;
        for (size_t i = 0; i < len; i++)
            a[i] = (rnd() % 4 == 0) ? 0 : (uint8_t)rnd();
        size_t el = tl_cobs_encode(a, len, enc);
        CHECK(el <= len + len / 254 + 1, "COBS overhead %zu for %zu", el, len);
        CHECK(memchr(enc, 0, el) == NULL, "COBS output has a zero");
        int32_t dl = tl_cobs_decode(enc, el, dec, sizeof dec);
        CHECK(dl == (int32_t)len && memcmp(a, dec, len) == 0, "COBS round trip len %zu", len);
    }
    /* every frame round-trips, and every single-bit flip of it is rejected */
    for (int n = 0; n < 300; n++) {
        uint8_t payload[TLP_MAX_PAYLOAD], wire[TLP_MAX_WIRE];
        uint8_t len = (uint8_t)(rnd() % (TLP_MAX_PAYLOAD + 1));
        for (int i = 0; i < len; i++)
            payload[i] = (uint8_t)rnd();
        uint16_t seq = (uint16_t)rnd();
        uint8_t cmd = (uint8_t)rnd();
        size_t wl = tl_frame_encode(seq, cmd, payload, len, wire, sizeof wire);
        tl_rx_t rx;
        tl_rx_init(&rx);
        tl_frame_t f;
        uint8_t st = 0;
        tl_rx_result_t r = TL_RX_NONE;
        for (size_t i = 0; i < wl; i++)
            r = tl_rx_byte(&rx, wire[i], &f, &st);
        CHECK(r == TL_RX_FRAME && f.seq == seq && f.cmd == cmd && f.len == len &&
                  memcmp(f.payload, payload, len) == 0, "frame round trip");
        for (size_t bit = 0; bit < (wl - 1) * 8; bit++) {
            uint8_t bad[TLP_MAX_WIRE];
            memcpy(bad, wire, wl);
            bad[bit / 8] ^= (uint8_t)(1u << (bit % 8));
            tl_rx_init(&rx);
            int frames = 0;
            for (size_t i = 0; i < wl; i++)
                if (tl_rx_byte(&rx, bad[i], &f, &st) == TL_RX_FRAME)
                    frames++;
            CHECK(frames == 0, "bit flip %zu of a %zu-byte frame accepted", bit, wl);
        }
        /* truncated then delimited: an error, and the next frame still parses */
        tl_rx_init(&rx);
        size_t cut = 1 + rnd() % (wl - 1);
        for (size_t i = 0; i < cut; i++)
            (void)tl_rx_byte(&rx, wire[i], &f, &st);
        r = tl_rx_byte(&rx, 0, &f, &st);
        CHECK(r == TL_RX_ERROR || cut == wl - 1 || cut == 1, "truncated frame (%zu of %zu) not an error", cut, wl);
        for (size_t i = 0; i < wl; i++)
            r = tl_rx_byte(&rx, wire[i], &f, &st);
        CHECK(r == TL_RX_FRAME && f.seq == seq, "resynchronised after a truncated frame");
    }
    /* oversize: a long run of non-zero bytes */
    tl_rx_t rx;
    tl_rx_init(&rx);
    tl_frame_t f;
    uint8_t st = 0;
    for (int i = 0; i < 500; i++)
        (void)tl_rx_byte(&rx, (uint8_t)(1 + rnd() % 255), &f, &st);
    CHECK(tl_rx_byte(&rx, 0, &f, &st) == TL_RX_ERROR && st == TLP_ST_OVERSIZE, "oversize status %u", st);
    /* len field disagreeing with the bytes: LENGTH (CRC made to match) */
    uint8_t pkt[8] = {1, 0, 7, 3, 9, 9}, enc[16];
    tl_put_u16(&pkt[6], 0);
    uint8_t body[6] = {1, 0, 7, 3, 9, 9};
    uint16_t crc = tl_crc16(body, 6, 0xFFFFu);
    tl_put_u16(&pkt[6], crc);
    size_t el = tl_cobs_encode(pkt, 8, enc);
    tl_rx_init(&rx);
    for (size_t i = 0; i < el; i++)
        (void)tl_rx_byte(&rx, enc[i], &f, &st);
    CHECK(tl_rx_byte(&rx, 0, &f, &st) == TL_RX_ERROR && st == TLP_ST_LENGTH, "length status %u", st);
    /* sequence window */
    tl_seq_t s = {0, false};
    CHECK(tl_seq_is_new(&s, 0x1234), "any first seq");
    tl_seq_accept(&s, 0xFFF0);
    CHECK(!tl_seq_is_new(&s, 0xFFF0), "same seq is a replay");
    CHECK(!tl_seq_is_new(&s, 0xFF00), "older seq is a replay");
    CHECK(tl_seq_is_new(&s, 0x0005), "wrap-around is new");
    CHECK(!tl_seq_is_new(&s, (uint16_t)(0xFFF0 + 0x8000)), "half-window ahead is not new");
}

/* ---- servo core on the fake HAL -------------------------------------------- */

static tl_servo_t sv;
static uint8_t last_reply[TLP_MAX_PACKET];
static int last_reply_len;
static uint16_t host_seq;
static tl_rx_t reply_rx;
static tl_auth_t host;        /* the host's half of the session: its key and the two nonces */
static bool host_tags;        /* send_cmd appends a MAC to every command but the reads */
static const uint8_t TEST_KEY[TLP_AUTH_KEY_BYTES] = {0x54, 0x4c, 0x6b, 0x65, 0x79, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11,
                                                     12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27};

static bool capture_tx(const uint8_t *wire, uint32_t len)
{
    tl_frame_t f;
    uint8_t st;
    for (uint32_t i = 0; i < len; i++) {
        if (tl_rx_byte(&reply_rx, wire[i], &f, &st) == TL_RX_FRAME) {
            last_reply[0] = f.cmd;
            memcpy(&last_reply[1], f.payload, f.len);
            last_reply_len = f.len;
        } else {
            CHECK(wire[i] != 0u || i == 0u || i == len - 1u, "reply frame must decode");
        }
    }
    return true;
}

static void feed(const uint8_t *wire, size_t len)
{
    for (size_t i = 0; i < len; i++)
        tl_servo_rx_byte(&sv, wire[i], capture_tx);
}

static bool is_read(uint8_t cmd)
{
    return cmd == TLP_CMD_IDENTIFY || cmd == TLP_CMD_GET_PARAM || cmd == TLP_CMD_STATUS || cmd == TLP_CMD_COUNTERS ||
           cmd == TLP_CMD_SESSION;
}

/* The wire bytes of a command, with its MAC in the host's session if tagged. */
static size_t encode_cmd(uint16_t seq, uint8_t cmd, const uint8_t *payload, uint8_t len, bool tagged, uint8_t *wire)
{
    uint8_t p[TLP_MAX_PAYLOAD];
    if (len)
        memcpy(p, payload, len);   /* HEARTBEAT has none (payload may be NULL) */
    if (tagged) {
        tl_auth_tag(&host, seq, cmd, p, len, &p[len]);
        len = (uint8_t)(len + TLP_AUTH_TAG_BYTES);
    }
    return tl_frame_encode(seq, cmd, p, len, wire, TLP_MAX_WIRE);
}

/* Send one command, return its status (reply payload byte 0). */
static uint8_t send_cmd(uint8_t cmd, const uint8_t *payload, uint8_t len)
{
    uint8_t wire[TLP_MAX_WIRE];
    size_t wl = encode_cmd(++host_seq, cmd, payload, len, host_tags && !is_read(cmd), wire);
    last_reply_len = -1;
    feed(wire, wl);
    CHECK(last_reply_len >= 1 && last_reply[0] == (cmd | TLP_REPLY_FLAG), "reply to 0x%02x", cmd);
    return last_reply[1];
}

static uint8_t set_param(uint8_t axis, uint8_t id, int32_t v)
{
    uint8_t p[6] = {axis, id};
    tl_put_u32(&p[2], (uint32_t)v);
    return send_cmd(TLP_CMD_SET_PARAM, p, 6);
}

static uint8_t enable(uint8_t mask, uint8_t on)
{
    uint8_t p[2] = {mask, on};
    return send_cmd(TLP_CMD_ENABLE, p, 2);
}

#define U TLP_MOVE_UNHOMED

static uint8_t move(uint8_t axis, uint8_t mode, int32_t target)
{
    uint8_t p[6] = {axis, mode};
    tl_put_u32(&p[2], (uint32_t)target);
    return send_cmd(TLP_CMD_MOVE, p, 6);
}

static uint8_t clear(uint8_t mask) { return send_cmd(TLP_CMD_CLEAR_FAULT, &mask, 1); }

/* SESSION: the board's nonce and proof; the host's half checks the proof and keeps the nonces. */
static uint8_t open_session(void)
{
    uint8_t hn[TLP_AUTH_NONCE_BYTES];
    for (uint32_t i = 0; i < sizeof hn; i++)
        hn[i] = (uint8_t)rnd();
    uint8_t st = send_cmd(TLP_CMD_SESSION, hn, sizeof hn);
    if (st != TLP_ST_OK)
        return st;
    memcpy(host.host_nonce, hn, sizeof hn);
    memcpy(host.board_nonce, &last_reply[1 + TLP_SESSION_REP_BOARD_NONCE], TLP_AUTH_NONCE_BYTES);
    /* the proof, computed here from its definition: HMAC(key, "TLSP" | host nonce | board nonce)[:16] */
    uint8_t m[4 + 2 * TLP_AUTH_NONCE_BYTES], mac[TL_SHA256_BYTES];
    memcpy(m, TLP_AUTH_LABEL_PROOF, 4);
    memcpy(&m[4], hn, sizeof hn);
    memcpy(&m[4 + sizeof hn], host.board_nonce, TLP_AUTH_NONCE_BYTES);
    tl_hmac(&host.key, m, sizeof m, mac);
    CHECK(memcmp(mac, &last_reply[1 + TLP_SESSION_REP_PROOF], TLP_AUTH_TAG_BYTES) == 0, "session proof");
    return st;
}

/* A board with the test key (key = false: built without one), the host holding that key, a session open. */
static void fresh_keyed(bool key)
{
    hal_fake_reset();
    if (key)
        hal_fake_set_key(TEST_KEY);
    tl_servo_init(&sv);
    tl_rx_init(&reply_rx);
    host_seq = (uint16_t)rnd();
    uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES];
    memcpy(slot, hal_fake.key_slot, sizeof slot);
    if (!key) {
        hal_fake_t save = hal_fake;
        hal_fake_set_key(TEST_KEY);
        memcpy(slot, hal_fake.key_slot, sizeof slot);
        hal_fake = save;
    }
    tl_auth_init(&host, slot);
    host_tags = false;
    if (key)
        CHECK(open_session() == TLP_ST_OK, "session");
    host_tags = key;
}

static void fresh(void) { fresh_keyed(true); }

static void ticks(int n)
{
    for (int i = 0; i < n; i++)
        tl_servo_tick(&sv);
}

static void test_servo_safety(void)
{
    fresh();
    CHECK(!hal_fake.pwm_on[0] && !hal_fake.pwm_on[1], "power-up: drives disabled");
    CHECK(move(0, U, 100) == TLP_ST_STATE, "move while disabled refused");
    ticks(5);
    CHECK(!hal_fake.pwm_on[0] && sv.ax[0].faults == 0, "power-up latch is not a fault");

    /* enable acknowledges the reset latch; the set-point starts at the position */
    hal_fake.enc[0].pos = 1234;
    CHECK(enable(1, 1) == TLP_ST_OK && hal_fake.pwm_on[0] && !(hal_fake.safety & TL_HAL_SAFE_FORCED), "enable");
    ticks(1);
    CHECK(hal_fake.pwm_cmd[0] == 0, "no jump on enable: cmd %" PRId32, hal_fake.pwm_cmd[0]);
    CHECK(move(0, 0, 1334) == TLP_ST_NOT_HOMED, "a move before homing needs the UNHOMED flag");
    CHECK(move(0, U, 1334) == TLP_ST_OK, "move");
    ticks(1);
    int32_t expect = (int32_t)(((((int64_t)sv.ax[0].ctl.kp_q16 * 100 * 65536) >> 16) + 32768) >> 16);
    CHECK(hal_fake.pwm_cmd[0] == expect, "P command %" PRId32 " expected %" PRId32, hal_fake.pwm_cmd[0], expect);

    /* replay: the same frame again is refused and not executed */
    uint8_t p[6] = {0, U};
    tl_put_u32(&p[2], 2000);
    uint8_t wire[TLP_MAX_WIRE];
    size_t wl = encode_cmd(++host_seq, TLP_CMD_MOVE, p, 6, true, wire);
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_OK, "first copy executed");
    (void)move(0, U, 1334);
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_REPLAY && (sv.ax[0].c.target_q16 >> 16) == 1334, "replay refused");

    /* e-stop: disabled in the same tick, latched, clear refused while pressed */
    hal_fake.safety |= TL_HAL_SAFE_ESTOP_IN | TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FORCED;
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && hal_fake.pwm_cmd[0] == 0 && (sv.ax[0].faults & TLP_FAULT_ESTOP), "e-stop");
    CHECK(clear(1) == TLP_ST_STATE && enable(1, 1) == TLP_ST_STATE, "clear refused while pressed");
    hal_fake.safety &= ~TL_HAL_SAFE_ESTOP_IN;
    CHECK(enable(1, 1) == TLP_ST_STATE, "enable refused while latched");
    CHECK(clear(3) == TLP_ST_OK && sv.ax[0].faults == 0 && sv.ax[1].faults == 0 && !hal_fake.pwm_on[0], "clear leaves it disabled");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable after clear");

    /* link watchdog */
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 1000) == TLP_ST_OK, "period");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 20) == TLP_ST_OK, "timeout");
    ticks(20);
    CHECK(hal_fake.pwm_on[0], "alive at the timeout");
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_LINK), "link silent -> stop");
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover");

    /* following error (the axis pushed away from its set-point) and soft limits */
    CHECK(set_param(0, TLP_P_FOLLOW_LIMIT, 50) == TLP_ST_OK, "follow limit");
    CHECK(move(0, U, 1234 + 51) == TLP_ST_RANGE, "a step beyond the following limit is refused up front");
    CHECK(move(0, U | TLP_MOVE_TRAPEZOID, 1234 + 51) == TLP_ST_OK, "a profiled move that far is fine");
    CHECK(move(0, U, 1234) == TLP_ST_OK, "back");
    hal_fake.enc[0].pos = 1234 - 51;
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_FOLLOWING), "following");
    hal_fake.enc[0].pos = 1234;
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover");
    CHECK(set_param(0, TLP_P_SOFT_MAX, 1300) == TLP_ST_OK, "soft max");
    CHECK(move(0, U, 1301) == TLP_ST_RANGE, "target beyond the soft limit");
    CHECK(set_param(0, TLP_P_SOFT_MIN, 1400) == TLP_ST_RANGE, "min above max refused");
    hal_fake.enc[0].pos = 1301;
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_SOFT_LIMIT), "soft limit");
    hal_fake.enc[0].pos = 1234;
    CHECK(clear(1) == TLP_ST_OK, "clear");

    /* bridge fault and encoder fault on axis 1; hardware-forced safe */
    CHECK(enable(2, 1) == TLP_ST_OK, "enable 1: faults %u safety 0x%x", sv.ax[1].faults, hal_fake.safety);
    hal_fake.enc[1].bridge_fault = true;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_BRIDGE), "bridge");
    CHECK(clear(2) == TLP_ST_STATE, "bridge fault present");
    hal_fake.enc[1].bridge_fault = false;
    CHECK(clear(2) == TLP_ST_OK && enable(2, 1) == TLP_ST_OK, "recover");
    hal_fake.enc[1].illegal = 3;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_ENCODER), "encoder");
    CHECK(clear(2) == TLP_ST_OK && hal_fake.enc[1].illegal == 0, "encoder clear resets the count");
    CHECK(enable(2, 1) == TLP_ST_OK, "recover");
    hal_fake.safety |= TL_HAL_SAFE_WDOG | TL_HAL_SAFE_FORCED;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_HW_SAFE), "hardware watchdog");
    CHECK(hal_fake.irq_depth == 0, "critical sections balanced");

    /* a new link rate is handed to main.c, which applies it once the reply has gone out */
    CHECK(sv.baud_div_pending == 0u && (int32_t)hal_fake.baud_div == TLP_PARAM_INFO[tl_param_index(TLP_P_BAUD_DIV)].dflt[0],
          "default baud divisor applied at init");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_BAUD_DIV, 5207) == TLP_ST_OK && sv.baud_div_pending == 5207u,
          "9600 baud pending");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_BAUD_DIV, 14) == TLP_ST_RANGE && sv.baud_div_pending == 5207u,
          "divisor below the UART's minimum refused");
}


static uint8_t get_param(uint8_t axis, uint8_t id, int32_t *v)
{
    uint8_t p[2] = {axis, id};
    uint8_t st = send_cmd(TLP_CMD_GET_PARAM, p, 2);
    *v = (int32_t)tl_get_u32(&last_reply[2]);
    return st;
}

static uint8_t status_of(uint8_t axis) { return send_cmd(TLP_CMD_STATUS, &axis, 1); }

static uint8_t home(uint8_t axis, uint8_t mode, uint8_t index)
{
    uint8_t p[3] = {axis, mode, index};
    return send_cmd(TLP_CMD_HOME, p, 3);
}

/* "A fault can be lost": axis 1's bridge fault latched in the SoC
 * but not yet seen by a control tick; a command for axis 0 must not
 * acknowledge it away (axis 1 would drive on), and a cause latching between
 * the firmware's read and its acknowledgement must survive. */
static void test_fault_race(void)
{
    for (int which = 0; which < 2; which++) {
        fresh();
        CHECK(enable(3, 1) == TLP_ST_OK, "enable both");
        ticks(1);
        hal_fake.safety |= TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_FORCED;   /* a glitch: latched, input gone */
        if (which == 0)
            CHECK(clear(1) == TLP_ST_OK, "CLEAR_FAULT for axis 0");
        else
            CHECK(enable(1, 1) == TLP_ST_OK, "ENABLE for axis 0");
        ticks(1);
        CHECK(!sv.ax[1].enabled && !hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_BRIDGE),
              "%s for axis 0 lost axis 1's latched bridge fault: enabled %d faults 0x%x",
              which ? "ENABLE" : "CLEAR_FAULT", sv.ax[1].enabled, sv.ax[1].faults);
        CHECK(enable(2, 1) == TLP_ST_STATE, "axis 1 stays off until its own CLEAR_FAULT");
    }
    /* a latch bit set after the read is not acknowledged by the write that follows */
    fresh();
    CHECK(enable(3, 1) == TLP_ST_OK, "enable both");
    hal_fake.latch_after_read = TL_HAL_SAFE_FAULT0;
    CHECK(clear(2) == TLP_ST_OK, "clear axis 1");
    CHECK(hal_fake.safety & TL_HAL_SAFE_FAULT0, "a bit latched after the read was acknowledged unseen");
    ticks(1);
    CHECK(!sv.ax[0].enabled && (sv.ax[0].faults & TLP_FAULT_BRIDGE), "axis 0 records it at the next tick");
    CHECK(hal_fake.irq_depth == 0, "critical sections balanced");
}

/* Encoder loss and runaway: a frozen, a reversed and a flickering encoder
 * trip RUNAWAY within STALL_MS (+ a few periods); an axis that follows does not.
 * At 1 ms the check runs every period; at 50 us every other period (servo_internal.h,
 * TL_RUNAWAY_EVERY_OTHER_BELOW_US): at most 2 periods later. */
static void test_runaway(void)
{
    enum { STALL_MS = 50 };
    const char *kinds[] = {"frozen", "reversed", "flickering", "following"};
    static const int periods[] = {1000, 50};
    for (int run = 0; run < 8; run++) {
        const int kind = run % 4, PERIOD = periods[run / 4];
        fresh();
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, PERIOD) == TLP_ST_OK, "period");
        CHECK(set_param(0, TLP_P_STALL_MS, STALL_MS) == TLP_ST_OK, "stall ms");
        CHECK(set_param(0, TLP_P_ENC_CMD0, 1023) == TLP_ST_OK, "the stall check alone (no plausibility check)");
        CHECK(set_param(0, TLP_P_KP_Q16, 65536) == TLP_ST_OK, "kp 1 step per count");
        CHECK(set_param(0, TLP_P_LAW, 3) == TLP_ST_OK && set_param(0, TLP_P_KI_Q16, 65536 * 4) == TLP_ST_OK, "pid");
        CHECK(enable(1, 1) == TLP_ST_OK, "enable");
        CHECK(move(0, U, 400) == TLP_ST_OK, "move 400 counts: command 400 > STALL_CMD 300");
        int n = 0;
        for (; n < STALL_MS * 1000 / PERIOD * 4 && sv.ax[0].enabled; n++) {
            if (n % 10 == 0)
                CHECK(send_cmd(TLP_CMD_HEARTBEAT, NULL, 0) == TLP_ST_OK, "heartbeat");
            int32_t c = hal_fake.pwm_cmd[0], before = hal_fake.enc[0].pos;
            if (kind == 1)
                hal_fake.enc[0].pos -= c > 0 ? 3 : (c < 0 ? -3 : 0);
            else if (kind == 2)
                hal_fake.enc[0].pos = (n & 1) ? 1 : 0;
            else if (kind == 3 && hal_fake.enc[0].pos < 400)
                hal_fake.enc[0].pos += 2;
            /* the decoder's clock and edge times (50 MHz) */
            hal_fake.enc[0].now += PERIOD * 50u;
            if (hal_fake.enc[0].pos != before) {
                hal_fake.enc[0].interval = hal_fake.enc[0].now - hal_fake.enc[0].edge_time;
                hal_fake.enc[0].edge_time = hal_fake.enc[0].now;
            }
            ticks(1);
        }
        if (kind == 3) {
            CHECK(sv.ax[0].enabled && sv.ax[0].faults == 0, "following axis: no fault (0x%x)", sv.ax[0].faults);
        } else {
            CHECK(!sv.ax[0].enabled && !hal_fake.pwm_on[0] && sv.ax[0].faults == TLP_FAULT_RUNAWAY,
                  "%s encoder: faults 0x%x", kinds[kind], sv.ax[0].faults);
            CHECK(n >= STALL_MS * 1000 / PERIOD && n <= STALL_MS * 1000 / PERIOD + 8,
                  "%s encoder tripped after %d periods of %d us, STALL_MS is %d", kinds[kind], n, PERIOD,
                  STALL_MS * 1000 / PERIOD);
        }
    }
}

/* Encoder plausibility on a plant that follows the check's own model (speed
 * 22.8 counts/s per step above a breakaway of 30 steps, time constant 20 ms;
 * the check configured for it: ENC_CMD0 30, ENC_TAU_MS 100): a P law
 * holding a command below STALL_CMD (85 steps) with the encoder frozen,
 * undercounting (1 count of 50), reversed or chattering trips RUNAWAY; a
 * healthy encoder through a move, a reversal and a stop never does. */
static void test_encoder_plausibility(void)
{
    const char *kinds[] = {"healthy", "frozen", "undercounting", "reversed", "chattering"};
    static const int periods[] = {1000, 50};   /* 50 us: the check runs every other period */
    for (int run = 0; run < 10; run++) {
        const int kind = run % 5, PERIOD = periods[run / 5], per_ms = 1000 / PERIOD;
        fresh();
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, PERIOD) == TLP_ST_OK, "period");
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 60000) == TLP_ST_OK, "timeout");
        CHECK(set_param(0, TLP_P_STALL_CMD, 100) == TLP_ST_OK, "STALL_CMD 10 %%");
        CHECK(set_param(0, TLP_P_KP_Q16, 65536) == TLP_ST_OK, "kp 1 step per count");
        CHECK(set_param(0, TLP_P_FOLLOW_LIMIT, 1000000) == TLP_ST_OK, "no following error");
        CHECK(set_param(0, TLP_P_ENC_CMD0, 30) == TLP_ST_OK && set_param(0, TLP_P_ENC_TAU_MS, 100) == TLP_ST_OK,
              "the check configured for this plant");
        CHECK(enable(1, 1) == TLP_ST_OK, "enable");
        double x = 0.0, v = 0.0;   /* the plant: counts, counts/s */
        int32_t target = 85, tripped_at = -1, max_travel = 0;
        CHECK(move(0, U, target) == TLP_ST_OK, "hold a command of 85 < STALL_CMD");
        for (int n = 0; n < 6000 * per_ms && sv.ax[0].enabled; n++) {
            if (kind == 0 && (n == 2000 * per_ms || n == 3000 * per_ms || n == 4000 * per_ms)) {
                target = n == 2000 * per_ms ? -300 : (n == 3000 * per_ms ? 800 : (int32_t)x);   /* reverse, go on, stop */
                CHECK(move(0, U, target) == TLP_ST_OK, "healthy: move to %" PRId32, target);
            }
            int32_t u = hal_fake.pwm_cmd[0];
            int32_t over = u > 30 ? u - 30 : (u < -30 ? u + 30 : 0);
            v += (22.8 * over - v) * (PERIOD * 1e-6 / 0.020);
            x += v * PERIOD * 1e-6;
            int32_t before = hal_fake.enc[0].pos, truth = (int32_t)(x >= 0 ? x + 0.5 : x - 0.5);
            if (kind == 0)
                hal_fake.enc[0].pos = truth;
            else if (kind == 2)
                hal_fake.enc[0].pos = truth / 50;
            else if (kind == 3)
                hal_fake.enc[0].pos = -truth;
            else if (kind == 4)
                hal_fake.enc[0].pos = n & 1;
            hal_fake.enc[0].now += PERIOD * 50u;
            if (hal_fake.enc[0].pos != before) {
                hal_fake.enc[0].interval = hal_fake.enc[0].now - hal_fake.enc[0].edge_time;
                hal_fake.enc[0].edge_time = hal_fake.enc[0].now;
            }
            if (n == 5 * per_ms && kind == 1)
                CHECK(u > 30 && u < 100, "the command is held below STALL_CMD: %" PRId32, u);
            ticks(1);
            if (!sv.ax[0].enabled)
                tripped_at = n / per_ms;
            int32_t travel = truth < 0 ? -truth : truth;
            if (travel > max_travel && kind != 0)
                max_travel = travel;
        }
        if (kind == 0) {
            CHECK(sv.ax[0].enabled && sv.ax[0].faults == 0, "healthy encoder at %d us: faults 0x%x", PERIOD,
                  sv.ax[0].faults);
        } else {
            CHECK(sv.ax[0].faults == TLP_FAULT_RUNAWAY && !hal_fake.pwm_on[0], "%s encoder: faults 0x%x",
                  kinds[kind], sv.ax[0].faults);
            /* ENC_SLACK 64 counts at least half the model's speed behind: the travel is bounded */
            CHECK(tripped_at >= 0 && max_travel < 600,
                  "%s encoder at %d us: tripped after %d ms, %" PRId32 " counts of travel", kinds[kind], PERIOD,
                  tripped_at, max_travel);
        }
    }
}

/* Safety limits may only be made stricter while an axis is enabled. */
static void test_tighten_only(void)
{
    /* the list must all be tighten-only */
    static const uint8_t must[] = {TLP_P_FOLLOW_LIMIT, TLP_P_SOFT_MIN, TLP_P_SOFT_MAX, TLP_P_LINK_TIMEOUT_MS,
                                   TLP_P_FDIV, TLP_P_PW0, TLP_P_PWMAX, TLP_P_CMD_LIMIT, TLP_P_PWM_MAX_HZ,
                                   TLP_P_STALL_CMD, TLP_P_STALL_MS, TLP_P_LIMIT_SW};
    for (unsigned k = 0; k < sizeof must; k++)
        CHECK(TLP_PARAM_INFO[tl_param_index(must[k])].tighten != 0, "param %u is not tighten-only", must[k]);
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++) {
        const tlp_param_info_t *in = &TLP_PARAM_INFO[k];
        if (!in->tighten)
            continue;
        uint8_t ax = in->global ? TLP_GLOBAL_AXIS : 0;
        fresh();
        /* a value one step inside the range from the default, both ways where possible */
        int32_t d = in->dflt[0];
        int32_t looser = in->tighten > 0 ? d - 1 : d + 1, stricter = in->tighten > 0 ? d + 1 : d - 1;
        if (in->id == TLP_P_FDIV) {
            looser = d - 10;
            stricter = d + 10;
        }
        if (in->id == TLP_P_PW0) {   /* default 0: make room first */
            CHECK(set_param(ax, TLP_P_PW0, 100) == TLP_ST_OK, "pw0 100");
            d = 100, looser = 101, stricter = 99;
        }
        bool can_loosen = looser >= in->min && looser <= in->max;
        CHECK(enable(2, 1) == TLP_ST_OK, "enable axis 1");
        if (can_loosen)
            CHECK(set_param(ax, in->id, looser) == TLP_ST_LOOSEN, "param %u: loosening to %" PRId32 " while enabled",
                  in->id, looser);
        int32_t v;
        CHECK(get_param(ax, in->id, &v) == TLP_ST_OK && v == d, "param %u unchanged: %" PRId32, in->id, v);
        if (stricter >= in->min && stricter <= in->max)
            CHECK(set_param(ax, in->id, stricter) == TLP_ST_OK, "param %u: tightening while enabled", in->id);
        CHECK(enable(3, 0) == TLP_ST_OK, "disable");
        if (can_loosen)
            CHECK(set_param(ax, in->id, looser) == TLP_ST_OK, "param %u: loosening while disabled", in->id);
    }
    /* the PWM carrier ceiling (IBT-2 25 kHz) and PW0 <= PWMAX */
    fresh();
    CHECK(set_param(0, TLP_P_FDIV, 1) == TLP_ST_RANGE, "FDIV 1 = 48.9 kHz is above the bridge's 25 kHz");
    CHECK(set_param(0, TLP_P_FDIV, 2) == TLP_ST_OK, "FDIV 2 = 24.4 kHz");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PWM_MAX_HZ, 20000) == TLP_ST_RANGE, "ceiling below axis 0's carrier");
    CHECK(set_param(0, TLP_P_FDIV, 3) == TLP_ST_OK && set_param(TLP_GLOBAL_AXIS, TLP_P_PWM_MAX_HZ, 20000) == TLP_ST_OK,
          "lower ceiling");
    CHECK(set_param(1, TLP_P_FDIV, 2) == TLP_ST_RANGE, "FDIV 2 above the lowered ceiling");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PWM_MAX_HZ, 25001) == TLP_ST_RANGE, "ceiling above the rating");
    CHECK(set_param(0, TLP_P_PWMAX, 500) == TLP_ST_OK && set_param(0, TLP_P_PW0, 501) == TLP_ST_RANGE, "PW0 > PWMAX");
    CHECK(set_param(0, TLP_P_PW0, 200) == TLP_ST_OK && set_param(0, TLP_P_PWMAX, 199) == TLP_ST_RANGE, "PWMAX < PW0");
    CHECK(hal_fake.fdiv[0] == 3 && hal_fake.pw0[0] == 200 && hal_fake.pwmax[0] == 500, "hardware has the stored values");
}

/* The link watchdog is fed only by commands that show the host in control. */
static void test_link_feed(void)
{
    fresh();
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 1000) == TLP_ST_OK, "period");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 20) == TLP_ST_OK, "timeout");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    int32_t v;
    for (int n = 0; n < 30 && sv.ax[0].enabled; n++) {
        /* a monitor that only polls, with fresh seqs, and IDENTIFY at any seq */
        (void)status_of(0);
        (void)get_param(0, TLP_P_LAW, &v);
        (void)send_cmd(TLP_CMD_COUNTERS, NULL, 0);
        (void)send_cmd(TLP_CMD_IDENTIFY, NULL, 0);
        ticks(1);
    }
    CHECK(!sv.ax[0].enabled && (sv.ax[0].faults & TLP_FAULT_LINK), "polls kept the axis enabled: faults 0x%x",
          sv.ax[0].faults);
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover");
    uint8_t wire[TLP_MAX_WIRE];
    size_t wl = encode_cmd(++host_seq, TLP_CMD_HEARTBEAT, NULL, 0, true, wire);   /* with its MAC */
    for (int n = 0; n < 60; n++) {
        if (n % 10 == 0)
            CHECK(send_cmd(TLP_CMD_HEARTBEAT, NULL, 0) == TLP_ST_OK, "heartbeat");
        ticks(1);
    }
    CHECK(sv.ax[0].enabled && sv.ax[0].faults == 0, "heartbeats keep it enabled");
    for (int n = 0; n < 30 && sv.ax[0].enabled; n++) {
        last_reply_len = -1;
        feed(wire, wl);   /* the same heartbeat replayed */
        CHECK(last_reply_len >= 1 && last_reply[1] == TLP_ST_REPLAY, "replayed heartbeat refused");
        ticks(1);
    }
    CHECK(!sv.ax[0].enabled && (sv.ax[0].faults & TLP_FAULT_LINK), "a replayed heartbeat fed the watchdog");
    /* anyone may STOP without the key, but that does not show the host in control */
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover again");
    host_tags = false;
    uint8_t m = 1;
    for (int n = 0; n < 30 && sv.ax[0].enabled; n++) {
        CHECK(send_cmd(TLP_CMD_STOP, &m, 1) == TLP_ST_OK, "stop without a MAC");
        ticks(1);
    }
    host_tags = true;
    CHECK(!sv.ax[0].enabled && (sv.ax[0].faults & TLP_FAULT_LINK), "STOPs without a MAC fed the watchdog");
    /* a recorded STOP with its MAC, replayed: it stops again, but shows no one in control */
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover a third time");
    wl = encode_cmd(++host_seq, TLP_CMD_STOP, &m, 1, true, wire);
    feed(wire, wl);
    for (int n = 0; n < 30 && sv.ax[0].enabled; n++) {
        last_reply_len = -1;
        feed(wire, wl);
        CHECK(last_reply_len >= 1 && last_reply[1] == TLP_ST_OK, "a replayed STOP still stops");
        ticks(1);
    }
    CHECK(!sv.ax[0].enabled && (sv.ax[0].faults & TLP_FAULT_LINK), "a replayed STOP fed the watchdog");
}

/* Someone who can write into the operator's stream puts a STATUS 0x4000 ahead of
 * the board's seq before each of the operator's frames: every command of the
 * operator is then stale, but STOP and disable run all the same, with a MAC or
 * without, and nothing else does. */
static void test_stop_cannot_be_blocked(void)
{
    for (int tagged = 0; tagged < 2; tagged++) {
        fresh();
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 1000) == TLP_ST_OK, "period");
        CHECK(enable(3, 1) == TLP_ST_OK && move(0, U, 900) == TLP_ST_OK, "moving");
        host_tags = tagged != 0;
        uint8_t wire[TLP_MAX_WIRE], ax = 0, m = 3;
        uint16_t seqs_before = sv.seq.last;
        for (int k = 0; k < 3; k++) {
            feed(wire, encode_cmd((uint16_t)(sv.seq.last + 0x4000u), TLP_CMD_STATUS, &ax, 1, false, wire));
            uint8_t st;
            if (k == 0)
                st = send_cmd(TLP_CMD_STOP, &m, 1);
            else if (k == 1)
                st = move(0, U, 1500);
            else
                st = enable(3, 0);
            uint8_t want = k != 1 ? TLP_ST_OK : (tagged ? TLP_ST_REPLAY : TLP_ST_AUTH);
            CHECK(st == want, "frame %d after an injected seq (tagged %d): status %u", k, tagged, st);
            if (k == 0)
                CHECK((sv.ax[0].c.target_q16 >> 16) == sv.ax[0].pos && sv.ax[0].enabled, "STOP held the position");
            if (k == 1)
                CHECK((sv.ax[0].c.target_q16 >> 16) == sv.ax[0].pos, "a stale MOVE ran");
        }
        CHECK(!sv.ax[0].enabled && !sv.ax[1].enabled, "disable ran although its seq was stale");
        CHECK(sv.seq.last != seqs_before, "the injected frames moved the seq on");
        host_tags = true;
    }
}

/* A soft-limit fault can be cleared while outside; the axis may then be enabled and
 * driven back in, never further out; once inside, the limits apply again. */
static void test_soft_limit_recovery(void)
{
    fresh();
    CHECK(set_param(0, TLP_P_SOFT_MAX, 1000) == TLP_ST_OK, "soft max");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    hal_fake.enc[0].pos = 1010;
    ticks(1);
    CHECK(!sv.ax[0].enabled && sv.ax[0].faults == TLP_FAULT_SOFT_LIMIT, "soft limit");
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "cleared and enabled outside the limit");
    CHECK(move(0, U, 1020) == TLP_ST_RANGE, "further out refused");
    CHECK(move(0, U | TLP_MOVE_TRAPEZOID, 990) == TLP_ST_OK, "back inside accepted");
    ticks(1);
    CHECK(sv.ax[0].enabled && sv.ax[0].faults == 0 && hal_fake.pwm_cmd[0] < 0, "driven back: cmd %" PRId32,
          hal_fake.pwm_cmd[0]);
    CHECK(move(0, U, 1000) == TLP_ST_OK, "step to the limit");
    hal_fake.enc[0].pos = 1015;    /* pushed further out: nothing drives outward */
    ticks(1);
    CHECK(sv.ax[0].enabled && hal_fake.pwm_cmd[0] <= 0, "no command outward: %" PRId32, hal_fake.pwm_cmd[0]);
    hal_fake.enc[0].pos = 995;     /* back inside */
    ticks(1);
    hal_fake.enc[0].pos = 1001;    /* out again: that is a fault */
    ticks(1);
    CHECK(!sv.ax[0].enabled && sv.ax[0].faults == TLP_FAULT_SOFT_LIMIT, "soft limit after the recovery");
}

/* Limit switches: a trip disables the axis and blocks only its direction. */
static void test_limit_switches(void)
{
    fresh();
    CHECK(hal_fake.limit_block[0] && hal_fake.limit_block[1], "hardware limit block on by default (LIMIT_SW 1)");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    CHECK(move(0, U, 100) == TLP_ST_OK, "move");
    ticks(1);
    CHECK(hal_fake.pwm_cmd[0] > 0, "driving positive");
    hal_fake.enc[0].limits = TL_HAL_LIM_POS;
    ticks(1);
    CHECK(!sv.ax[0].enabled && sv.ax[0].faults == TLP_FAULT_LIMIT_POS && hal_fake.pwm_cmd[0] == 0, "limit trips");
    CHECK(status_of(0) == TLP_ST_OK && last_reply[1 + TLP_STATUS_REP_LIMITS] == TLP_LIMIT_POS, "STATUS shows the switch");
    CHECK(clear(1) == TLP_ST_STATE && sv.ax[0].faults == TLP_FAULT_LIMIT_POS, "clear refused while the switch is open");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable with a direction fault");
    ticks(3);
    CHECK(sv.ax[0].enabled, "the latched direction fault does not stop it again");
    CHECK(move(0, U, 50) == TLP_ST_RANGE, "toward the switch refused");
    CHECK(move(0, U, -50) == TLP_ST_OK, "away from it accepted");
    ticks(1);
    CHECK(hal_fake.pwm_cmd[0] < 0 && sv.ax[0].enabled, "driven out");
    hal_fake.enc[0].pos = -10;
    hal_fake.enc[0].limits = 0;
    ticks(1);
    CHECK(move(0, U, 40) == TLP_ST_RANGE, "still blocked until cleared");
    CHECK(clear(1) == TLP_ST_OK && sv.ax[0].faults == 0, "cleared once out");
    CHECK(enable(1, 1) == TLP_ST_OK && move(0, U, 40) == TLP_ST_OK, "free again");
    /* an axis without switches ignores its inputs */
    CHECK(enable(1, 0) == TLP_ST_OK && set_param(0, TLP_P_LIMIT_SW, 0) == TLP_ST_OK, "no switches");
    CHECK(!hal_fake.limit_block[0], "hardware block off");
    hal_fake.enc[0].limits = TL_HAL_LIM_NEG | TL_HAL_LIM_POS;
    ticks(1);
    CHECK(sv.ax[0].faults == 0, "inputs ignored with LIMIT_SW 0");
    CHECK(enable(1, 1) == TLP_ST_OK && set_param(0, TLP_P_LIMIT_SW, 1) == TLP_ST_OK, "switches back on (tighter)");
    ticks(1);
    CHECK(!sv.ax[0].enabled && sv.ax[0].faults == (TLP_FAULT_LIMIT_NEG | TLP_FAULT_LIMIT_POS), "unwired reads open");
}

/* Homing: moves need it (or the UNHOMED flag); to a switch, then optionally the
 * index; afterwards positions and soft limits are absolute. */
static void test_homing(void)
{
    for (int index = 0; index < 2; index++) {
        fresh();
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 1000) == TLP_ST_OK, "period");
        CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 60000) == TLP_ST_OK, "timeout");
        CHECK(set_param(0, TLP_P_HOME_VEL, 20000) == TLP_ST_OK && set_param(0, TLP_P_HOME_POS, -7) == TLP_ST_OK, "home");
        hal_fake.enc[0].pos = 5000;
        CHECK(enable(1, 1) == TLP_ST_OK, "enable");
        CHECK(move(0, 0, 5100) == TLP_ST_NOT_HOMED, "not homed");
        /* every path that moves the soft-limit window is closed while an axis is enabled */
        CHECK(home(0, TLP_HOME_MODE_NEG, (uint8_t)index) == TLP_ST_STATE, "switch homing while enabled");
        CHECK(home(0, TLP_HOME_MODE_HERE, 0) == TLP_ST_STATE, "home here while enabled");
        CHECK(enable(1, 0) == TLP_ST_OK && enable(2, 1) == TLP_ST_OK, "the other axis enabled");
        CHECK(home(0, TLP_HOME_MODE_NEG, (uint8_t)index) == TLP_ST_STATE, "homing while another axis is enabled");
        CHECK(set_param(0, TLP_P_HOME_POS, 900000) == TLP_ST_LOOSEN && set_param(0, TLP_P_HOME_POS, -7) == TLP_ST_OK,
              "HOME_POS frozen while an axis is enabled");
        CHECK(enable(2, 0) == TLP_ST_OK, "all disabled");
        CHECK(home(0, TLP_HOME_MODE_HERE, 0) == TLP_ST_STATE, "home here with limit switches declared");
        CHECK(home(0, TLP_HOME_MODE_NEG, (uint8_t)index) == TLP_ST_OK && sv.ax[0].enabled,
              "home toward the negative switch: it enables the axis");
        CHECK(move(0, U, 5100) == TLP_ST_STATE, "no move while homing");
        /* the stage: follows its set-point; the switch opens below raw count 1000,
         * an index every 400 counts */
        int32_t last = hal_fake.enc[0].pos;
        int n = 0;
        for (; n < 20000 && sv.ax[0].home == TLP_HOME_STATE_HOMING; n++) {
            int32_t sp = (int32_t)(sv.ax[0].c.sp_q16 >> 16) - sv.ax[0].offset;
            hal_fake.enc[0].now += 1000u * 50u;    /* the decoder's clock and edge times (1 ms periods) */
            if (sp != hal_fake.enc[0].pos) {
                hal_fake.enc[0].interval = hal_fake.enc[0].now - hal_fake.enc[0].edge_time;
                hal_fake.enc[0].edge_time = hal_fake.enc[0].now;
            }
            hal_fake.enc[0].pos = sp;
            hal_fake.enc[0].limits = sp < 1000 ? TL_HAL_LIM_NEG : 0u;
            if (hal_fake.index_armed[0] && sp / 400 != last / 400 && !hal_fake.index_seen[0]) {
                hal_fake.index_seen[0] = true;
                hal_fake.index_pos[0] = sp > last ? sp / 400 * 400 : last / 400 * 400;
            }
            last = sp;
            ticks(1);
        }
        CHECK(sv.ax[0].home == TLP_HOME_STATE_HOMED && sv.ax[0].faults == 0 && sv.ax[0].enabled,
              "homed (index %d) after %d periods: state %u faults 0x%x", index, n, sv.ax[0].home, sv.ax[0].faults);
        int32_t ref = index ? 1200 : 1000;   /* the switch closes at 1000; the next index above is 1200 */
        CHECK(sv.ax[0].pos - (hal_fake.enc[0].pos - ref) == -7, "home point reads HOME_POS: pos %" PRId32 " raw %" PRId32,
              sv.ax[0].pos, hal_fake.enc[0].pos);
        CHECK(status_of(0) == TLP_ST_OK && last_reply[1 + TLP_STATUS_REP_HOME] == TLP_HOME_STATE_HOMED, "STATUS homed");
        CHECK(move(0, 0, 100) == TLP_ST_OK, "moves without the flag once homed");
        /* soft limits are absolute now */
        CHECK(set_param(0, TLP_P_SOFT_MIN, -10) == TLP_ST_OK, "soft min");
        CHECK(move(0, 0, -11) == TLP_ST_RANGE, "below the absolute soft limit");
    }
    /* no switches: home here */
    fresh();
    CHECK(set_param(0, TLP_P_LIMIT_SW, 0) == TLP_ST_OK, "no switches");
    hal_fake.enc[0].pos = 777;
    CHECK(home(0, TLP_HOME_MODE_NEG, 0) == TLP_ST_STATE && !sv.ax[0].enabled, "switch homing without switches refused");
    CHECK(home(0, TLP_HOME_MODE_HERE, 0) == TLP_ST_OK && sv.ax[0].pos == 0 && sv.ax[0].home == TLP_HOME_STATE_HOMED,
          "home here: %" PRId32, sv.ax[0].pos);
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    ticks(2);
    CHECK(hal_fake.pwm_cmd[0] == 0 && sv.ax[0].faults == 0, "no jump after homing here");
    /* an encoder fault loses the home */
    hal_fake.enc[0].illegal = 1;
    ticks(1);
    CHECK(sv.ax[0].home == TLP_HOME_STATE_NOT_HOMED, "encoder fault: not homed any more");
}

/* GET reads back what SET stored, at every gain the firmware accepts. */
static void test_gain_readback(void)
{
    fresh();
    int32_t v;
    int32_t tau = TLP_PARAM_INFO[tl_param_index(TLP_P_TAU_MAX_MNM)].dflt[0];
    int32_t cpr = TLP_PARAM_INFO[tl_param_index(TLP_P_COUNTS_PER_REV)].dflt[0];
    int32_t rmax = tl_gain_raw_from_phys(100000000, tau, cpr);
    CHECK(set_param(0, TLP_P_KP_Q16, rmax + 1) == TLP_ST_RANGE, "a raw gain beyond 100 N m/rad refused");
    CHECK(set_param(0, TLP_P_KP_Q16, 0x7FFFFFFF) == TLP_ST_RANGE, "the largest raw gain refused");
    CHECK(set_param(0, TLP_P_KP_Q16, rmax) == TLP_ST_OK && get_param(0, TLP_P_KP_UNM_RAD, &v) == TLP_ST_OK &&
              llabs((long long)v - 100000000) < 100, "raw max reads about 100 N m/rad: %" PRId32, v);
    CHECK(set_param(0, TLP_P_TAU_MAX_MNM, tau + 1000) == TLP_ST_RANGE, "tau change that pushes the gain out of range");
    for (int n = 0; n < 200; n++) {
        int32_t g = (int32_t)(rnd() % 100000001u);
        uint8_t id = (uint8_t)(TLP_P_KP_UNM_RAD + rnd() % 3);
        (void)set_param(0, TLP_P_TAU_MAX_MNM, (int32_t)(1 + rnd() % 100000));   /* refused if a gain no longer fits */
        uint8_t st = set_param(0, id, g);
        int32_t echo = (int32_t)tl_get_u32(&last_reply[2]);
        if (st != TLP_ST_OK)
            continue;
        CHECK(get_param(0, id, &v) == TLP_ST_OK && v == echo, "GET %" PRId32 " != SET echo %" PRId32, v, echo);
        CHECK(llabs((long long)echo - g) <= (long long)g / 1000 + 20000, "stored %" PRId32 " for %" PRId32, echo, g);
        CHECK(set_param(0, id, 0) == TLP_ST_OK, "zero");
    }
}

/* The encoder count wraps at 2^32 without undefined behaviour (UBSan in this build). */
static void test_encoder_wrap(void)
{
    for (uint32_t mode = 0; mode < 2; mode++) {
        tl_ctl_params_t p = {.law = 1, .kp_q16 = 1000, .cmd_limit = 1023, .vel_mode = mode, .vmax_cps = 1000,
                             .amax_cps2 = 1000};
        tl_ctl_t c = {0};
        tl_ctl_derive(&c, &p, 1000, 50000000u);
        int32_t pos = INT32_MAX - 20;
        tl_ctl_reset(&c, pos, 0);
        uint32_t t = 0;
        for (int k = 0; k < 8; k++) {
            pos = (int32_t)((uint32_t)pos + 10u);   /* 10 counts per 1 ms: 10000 counts/s */
            t += 50000u;
            (void)tl_ctl_step(&c, &p, pos, t, t, 5000u, false);
        }
        CHECK(pos < 0 && c.vel_q8 > 0 && llabs((long long)c.vel_q8 - 10000 * 256) < 10000 * 256 / 10,
              "velocity across the wrap (mode %u): %" PRId32, mode, c.vel_q8);
    }
    fresh();
    hal_fake.enc[0].pos = INT32_MAX - 2;
    CHECK(set_param(0, TLP_P_LIMIT_SW, 0) == TLP_ST_OK && home(0, TLP_HOME_MODE_HERE, 0) == TLP_ST_OK, "home near the wrap");
    CHECK(set_param(0, TLP_P_HOME_POS, INT32_MAX) == TLP_ST_OK && home(0, TLP_HOME_MODE_HERE, 0) == TLP_ST_OK, "re-home");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    hal_fake.enc[0].pos = INT32_MIN + 2;    /* 5 counts on, across the wrap */
    ticks(3);
    CHECK(sv.ax[0].pos == INT32_MIN + 4 && (sv.ax[0].faults & TLP_FAULT_FOLLOWING) && !sv.ax[0].enabled,
          "offset arithmetic wraps: %" PRId32 ", faults 0x%x", sv.ax[0].pos, sv.ax[0].faults);
}

static uint32_t get_kp(void)
{
    uint8_t p[2] = {0, TLP_P_KP_Q16};
    CHECK(send_cmd(TLP_CMD_GET_PARAM, p, 2) == TLP_ST_OK, "get");
    return tl_get_u32(&last_reply[1 + TLP_GET_PARAM_REP_VALUE]);
}

/* Who may change the machine (docs/security.md). */
static void test_servo_auth(void)
{
    /* a board built without a key: refuses what needs one and says why; reading and stopping work */
    fresh_keyed(false);
    CHECK(open_session() == TLP_ST_NO_KEY, "SESSION on a board without a key");
    CHECK(enable(1, 1) == TLP_ST_NO_KEY && !hal_fake.pwm_on[0], "enable without a key on the board");
    host_tags = true;
    CHECK(enable(1, 1) == TLP_ST_NO_KEY && set_param(0, TLP_P_KP_Q16, 5) == TLP_ST_NO_KEY, "tagged, no key");
    host_tags = false;
    uint8_t m = 1;
    CHECK(send_cmd(TLP_CMD_STOP, &m, 1) == TLP_ST_OK && enable(3, 0) == TLP_ST_OK, "stop and disable need no key");
    CHECK(sv.cnt.auth == 3, "refusals counted: %u", sv.cnt.auth);

    /* a keyed board: without a MAC nothing that changes the machine runs */
    fresh();
    host_tags = false;
    hal_fake.enc[0].pos = 500;
    uint32_t kp = get_kp();
    CHECK(enable(1, 1) == TLP_ST_AUTH && !hal_fake.pwm_on[0] && !sv.ax[0].enabled, "enable without a MAC");
    CHECK(set_param(0, TLP_P_KP_Q16, 5) == TLP_ST_AUTH && get_kp() == kp, "set without a MAC");
    uint8_t magic[4];
    tl_put_u32(magic, TLP_BOOTLOADER_MAGIC);
    CHECK(send_cmd(TLP_CMD_BOOTLOADER, magic, 4) == TLP_ST_AUTH && !sv.bootloader_req, "bootloader without a MAC");
    CHECK(clear(1) == TLP_ST_AUTH, "clear without a MAC");
    host_tags = true;
    CHECK(enable(1, 1) == TLP_ST_OK && hal_fake.pwm_on[0], "enable with the MAC");
    CHECK(move(0, U, 700) == TLP_ST_OK && (sv.ax[0].c.target_q16 >> 16) == 700, "move with the MAC");
    /* a MAC off by one bit, or for another command, or another session's: refused, nothing moves */
    uint8_t p[6] = {0, U}, wire[TLP_MAX_WIRE];
    tl_put_u32(&p[2], 900);
    for (int bit = 0; bit < 8 * (int)TLP_AUTH_TAG_BYTES; bit += 5) {
        uint8_t q[6 + TLP_AUTH_TAG_BYTES];
        memcpy(q, p, 6);
        tl_auth_tag(&host, (uint16_t)(host_seq + 1), TLP_CMD_MOVE, q, 6, &q[6]);
        q[6 + bit / 8] ^= (uint8_t)(1u << (bit % 8));
        feed(wire, tl_frame_encode(++host_seq, TLP_CMD_MOVE, q, sizeof q, wire, sizeof wire));
        CHECK(last_reply[1] == TLP_ST_AUTH && (sv.ax[0].c.target_q16 >> 16) == 700, "tag bit %d flipped", bit);
    }
    /* replay: the same authenticated frame again is refused and not executed twice */
    size_t wl = encode_cmd(++host_seq, TLP_CMD_MOVE, p, 6, true, wire);
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_OK && (sv.ax[0].c.target_q16 >> 16) == 900, "first copy");
    CHECK(move(0, U, 800) == TLP_ST_OK, "move");
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_REPLAY && (sv.ax[0].c.target_q16 >> 16) == 800, "replayed MOVE refused");
    /* ... also after someone without the key walked the link's seq all the way round: the
     * session's own count refuses it (unauthenticated frames cannot move that one) */
    uint16_t replay_seq = 0;
    {
        tl_frame_t f;
        uint8_t st;
        tl_rx_t r;
        tl_rx_init(&r);
        for (size_t i = 0; i < wl; i++)
            if (tl_rx_byte(&r, wire[i], &f, &st) == TL_RX_FRAME)
                replay_seq = f.seq;
    }
    host_tags = false;
    for (int k = 0; k < 10 && !tl_seq_is_new(&sv.seq, replay_seq); k++) {
        host_seq = (uint16_t)(host_seq + 0x7000u);
        uint8_t ax = 0;
        CHECK(send_cmd(TLP_CMD_STATUS, &ax, 1) == TLP_ST_OK, "status %d", k);
    }
    CHECK(tl_seq_is_new(&sv.seq, replay_seq), "the link's seq guard alone would take the old frame");
    feed(wire, wl);
    CHECK(last_reply[1] != TLP_ST_OK && (sv.ax[0].c.target_q16 >> 16) == 800, "old MOVE replayed after the seq wrapped");
    /* the session's range: a host that left it opens a new one */
    host_tags = true;
    CHECK(open_session() == TLP_ST_OK && move(0, U, 810) == TLP_ST_OK, "new session");
    /* tags of the old session do not verify in the new one */
    tl_auth_t old = host;
    CHECK(open_session() == TLP_ST_OK, "another session");
    tl_auth_t cur = host;
    host = old;
    CHECK(move(0, U, 820) == TLP_ST_AUTH && (sv.ax[0].c.target_q16 >> 16) == 810, "stale session's MAC");
    host = cur;
    CHECK(memcmp(old.board_nonce, cur.board_nonce, TLP_AUTH_NONCE_BYTES) != 0, "fresh challenge");
    /* a host with another key: the session proof tells, and its MACs are refused */
    tl_auth_t wrong;
    uint8_t other[TLP_AUTH_KEY_BYTES] = {9};
    hal_fake_t save = hal_fake;
    hal_fake_set_key(other);
    tl_auth_init(&wrong, hal_fake.key_slot);
    hal_fake = save;
    memcpy(wrong.host_nonce, host.host_nonce, TLP_AUTH_NONCE_BYTES);
    memcpy(wrong.board_nonce, host.board_nonce, TLP_AUTH_NONCE_BYTES);
    host = wrong;
    CHECK(move(0, U, 830) == TLP_ST_AUTH && (sv.ax[0].c.target_q16 >> 16) == 810, "wrong key");
    /* stopping is always allowed: STOP and disable without any MAC */
    host_tags = false;
    m = 1;
    CHECK(send_cmd(TLP_CMD_STOP, &m, 1) == TLP_ST_OK && (sv.ax[0].c.target_q16 >> 16) == 500, "stop without a MAC");
    CHECK(enable(1, 0) == TLP_ST_OK && !hal_fake.pwm_on[0] && !sv.ax[0].enabled, "disable without a MAC");
    CHECK(hal_fake.irq_depth == 0, "critical sections balanced");
}

/* Random and corrupted traffic: no parameter, enable or set-point changes. */
static void test_servo_flood(void)
{
    fresh();
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    tl_servo_t before = sv;
    hal_fake_t hw = hal_fake;
    uint8_t templ[TLP_MAX_WIRE];
    uint8_t p[6] = {0, 0, 0x10, 0x27, 0, 0};
    size_t tl = tl_frame_encode((uint16_t)(host_seq + 1), TLP_CMD_MOVE, p, 6, templ, sizeof templ);
    unsigned frames = 0;
    for (int n = 0; n < 20000; n++) {
        uint8_t buf[200];
        size_t len;
        if (rnd() % 2) {
            len = rnd() % sizeof buf;
            for (size_t i = 0; i < len; i++)
                buf[i] = (uint8_t)rnd();
        } else {
            memcpy(buf, templ, tl);
            len = tl;
            int flips = 1 + (int)(rnd() % 3);
            for (int k = 0; k < flips; k++)
                buf[rnd() % (tl - 1)] ^= (uint8_t)(1u << (rnd() % 8));
            if (memcmp(buf, templ, tl) == 0)
                continue;   /* two flips of the same bit: that is the valid frame itself */
        }
        feed(buf, len);
        feed((const uint8_t *)"\0", 1);
        frames++;
    }
    /* a 2^-16 chance per random frame of a valid CRC: count only what the firmware accepted */
    CHECK(sv.cnt.frames_ok == before.cnt.frames_ok, "accepted %u frames of noise", sv.cnt.frames_ok - before.cnt.frames_ok);
    CHECK(memcmp(sv.ax[0].p, before.ax[0].p, sizeof sv.ax[0].p) == 0 &&
              memcmp(sv.ax[1].p, before.ax[1].p, sizeof sv.ax[1].p) == 0 && memcmp(sv.g, before.g, sizeof sv.g) == 0,
          "parameters changed by noise");
    CHECK(sv.ax[0].c.target_q16 == before.ax[0].c.target_q16 && sv.ax[0].enabled && !sv.ax[1].enabled &&
              hal_fake.pwm_on[0] == hw.pwm_on[0] && hal_fake.pwm_on[1] == hw.pwm_on[1],
          "motion state changed by noise");
    unsigned errs = (unsigned)sv.cnt.crc + sv.cnt.framing + sv.cnt.length + sv.cnt.oversize;
    CHECK(errs + 50u >= frames, "errors counted %u of %u chunks", errs, frames);
    printf("flood: %u chunks, %u counted as errors\n", frames, errs);
}

/* Trapezoid: speed <= vmax, speed change <= amax per sample, lands exactly, never overshoots. */
static void test_profile(void)
{
    for (int n = 0; n < 300; n++) {
        tl_ctl_params_t p = {.law = 1, .kp_q16 = 1000, .cmd_limit = 1023, .vel_mode = 1,
                             .vmax_cps = (int32_t)(1 + rnd() % 200000), .amax_cps2 = (int32_t)(1 + rnd() % 5000000)};
        tl_ctl_t c = {0};
        uint32_t period = 200 + rnd() % 24800;
        tl_ctl_derive(&c, &p, period, 50000000u);
        int32_t start = (int32_t)(rnd() % 20000) - 10000, target = (int32_t)(rnd() % 20000) - 10000;
        tl_ctl_reset(&c, start, 0);
        tl_ctl_move(&c, target, true);
        int64_t prev_v = 0, prev_sp = c.sp_q16;
        int steps = 0;
        bool ok = true;
        while (c.moving && steps < 2000000) {
            (void)tl_ctl_step(&c, &p, start, 0, 0, 0, false);
            int64_t v = c.sp_q16 - prev_sp;
            int64_t dv = v - prev_v;
            if ((v < 0 ? -v : v) > c.d.vmax_q16 + c.d.amax_q16 || (dv < 0 ? -dv : dv) > c.d.amax_q16)
                ok = false;
            int64_t before = (int64_t)target * 65536 - prev_sp, after = (int64_t)target * 65536 - c.sp_q16;
            if ((before > 0 && after < 0) || (before < 0 && after > 0))
                ok = false;
            prev_v = v;
            prev_sp = c.sp_q16;
            steps++;
        }
        CHECK(ok && !c.moving && c.sp_q16 == (int64_t)target * 65536,
              "profile %d: vmax %" PRId32 " amax %" PRId32 " period %" PRIu32 " %d steps", n, p.vmax_cps, p.amax_cps2,
              period, steps);
    }
}

/* ---- line-driven control for the Python reference comparison ---------------- */

static int ctl_main(void)
{
    static tl_axis_t ea;   /* enc_check's state and inputs */
    int32_t enc_cmd0 = 0, enc_slack = 0;
    tl_ctl_params_t p = {0};
    tl_ctl_t c;
    memset(&c, 0, sizeof c);
    uint32_t period = 1000;
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        long long a[18] = {0};
        char op = line[0];
        int n = sscanf(line + 1,
                       "%lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld",
                       &a[0], &a[1], &a[2], &a[3], &a[4], &a[5], &a[6], &a[7], &a[8], &a[9], &a[10], &a[11], &a[12],
                       &a[13], &a[14], &a[15], &a[16], &a[17]);
        (void)n;
        switch (op) {
        case 'P':
            p = (tl_ctl_params_t){(uint32_t)a[0], (int32_t)a[1], (int32_t)a[2], (int32_t)a[3], (int32_t)a[4],
                                  (int32_t)a[5], (uint32_t)a[6], (int32_t)a[7], (int32_t)a[8],
                                  (int32_t)a[10], (int32_t)a[11], (int32_t)a[12], (int32_t)a[13],
                                  (int32_t)a[14], a[15] > 0 ? (int32_t)a[15] : 1, (int32_t)a[16]};
            period = (uint32_t)a[9];
            tl_ctl_derive(&c, &p, period, 50000000u);
            break;
        case 'R': tl_ctl_reset(&c, (int32_t)a[0], (uint32_t)a[1]); break;
        case 'M': tl_ctl_move(&c, (int32_t)a[0], a[1] != 0); break;
        case 'S': {
            int32_t cmd = tl_ctl_step(&c, &p, (int32_t)a[0], (uint32_t)a[1], (uint32_t)a[2], (uint32_t)a[4], a[3] != 0);
            printf("%" PRId32 " %" PRId64 " %" PRId32 " %" PRId64 " %" PRId32 "\n", cmd, c.sp_q16, c.vel_q8, c.integ_q32,
                   c.prof_a_q16);
            break;
        }
        case 'D': {   /* tl_div64_32(hi:lo, d) */
            uint64_t n = ((uint64_t)(uint32_t)a[0] << 32) | (uint32_t)a[1];
            printf("%" PRIu32 "\n", tl_div64_32(n, (uint32_t)a[2]));
            break;
        }
        case 'G':
            printf("%" PRId32 " %" PRId32 "\n", tl_gain_raw_from_phys((int32_t)a[0], (int32_t)a[1], (int32_t)a[2]),
                   tl_gain_phys_from_raw((int32_t)a[3], (int32_t)a[1], (int32_t)a[2]));
            break;
        case 'E':   /* encoder plausibility: cmd0 cps tau_ms slack period_us */
            enc_check_derive(&ea.enc, (int32_t)a[1], (int32_t)a[2], (uint32_t)a[4]);
            enc_check_reset(&ea);
            enc_cmd0 = (int32_t)a[0];
            enc_slack = (int32_t)a[3];
            break;
        case 'e': { /* one period: cmd pos vel_q8 */
            ea.cmd = (int32_t)a[0];
            ea.pos = (int32_t)a[1];
            ea.c.vel_q8 = (int32_t)a[2];
            uint16_t f = enc_check(&ea, enc_cmd0, enc_slack);
            printf("%d %" PRId32 " %" PRId64 "\n", f != 0, ea.enc_vlo_q8, ea.enc_exp_q24);
            break;
        }
        default: break;
        }
    }
    return 0;
}

/* Telemetry's cadence (tl_servo_telemetry_due, the main loop's): a record due at each
 * multiple of TELEMETRY's every, once; a loop too late for some records gets one, the next
 * again at a multiple; 0 stops them. */
static void test_telemetry_cadence(void)
{
    fresh();
    ticks(37);
    uint8_t q[2];
    tl_put_u16(q, 20);
    CHECK(send_cmd(TLP_CMD_TELEMETRY, q, 2) == TLP_ST_OK, "telemetry every 20");
    uint32_t due[8], n = 0;
    for (int k = 0; k < 60; k++) {
        ticks(1);
        if (tl_servo_telemetry_due(&sv) && n < 8)
            due[n++] = sv.ticks;
        CHECK(!tl_servo_telemetry_due(&sv), "a record is due once (period %u)", sv.ticks);
    }
    CHECK(n == 3 && due[0] == 40 && due[1] == 60 && due[2] == 80, "due at 40, 60, 80: %u records, first %u",
          n, n ? due[0] : 0u);
    ticks(45);   /* 142: the loop missed 100, 120 and 140 */
    CHECK(tl_servo_telemetry_due(&sv) && !tl_servo_telemetry_due(&sv), "a late loop gets one record");
    ticks(17);
    CHECK(!tl_servo_telemetry_due(&sv), "none before 160");
    ticks(1);
    CHECK(tl_servo_telemetry_due(&sv), "the next at 160, a multiple again");
    tl_put_u16(q, 0);
    CHECK(send_cmd(TLP_CMD_TELEMETRY, q, 2) == TLP_ST_OK, "telemetry off");
    ticks(100);
    CHECK(!tl_servo_telemetry_due(&sv), "off: none due");
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "ctl") == 0)
        return ctl_main();
    uint64_t seed = argc >= 3 ? strtoull(argv[2], NULL, 0) : 0x5EEDu;
    rng_state = seed ? seed : 1u;
    printf("seed %" PRIu64 "\n", seed);
    test_link();
    test_servo_safety();
    test_fault_race();
    test_runaway();
    test_tighten_only();
    test_link_feed();
    test_stop_cannot_be_blocked();
    test_encoder_plausibility();
    test_soft_limit_recovery();
    test_limit_switches();
    test_homing();
    test_gain_readback();
    test_encoder_wrap();
    test_servo_auth();
    test_servo_flood();
    test_profile();
    test_telemetry_cadence();
    printf("%u checks, %u failures\n", checks, failures);
    return failures ? 1 : 0;
}
