// SPDX-License-Identifier: MIT
// Native Verilator harness of the co-simulation: the board image
// (torqueloop/sim/harness/rtl_loop_top.v) with its clock, its encoder pins and its
// UART line driven from C++, behind a narrow C interface that Python
// (torqueloop/sim/native.py, ctypes) calls.  Python is woken only when a
// bridge pin changes or a cycle budget ends, never per clock:
//   - encoder edges arrive as a list of (cycle, axis, A, B, Z) that the
//     harness applies before the rising clock edge of that cycle;
//   - the UART line is a byte serialiser (host -> FPGA) and a mid-bit
//     sampling deserialiser (FPGA -> host) at a given clocks-per-bit,
//     the same framing as the RN-XV (8N1);
//   - the run stops at the first clock after which any bridge pin
//     (RPWM, LPWM, R_EN, L_EN of either axis) differs from before.
// Time: cycle n is the n-th rising edge of CLOCK_50; outputs read after it
// hold from n * 20 ns on.
//
// Evaluation (compile-time switches, set by native.py's Variant):
//   TL_EVAL_PER_CLOCK 2: eval() at the rising and at the falling edge, the
//     textbook loop and Verilator's public API only;
//   TL_EVAL_PER_CLOCK 1: one evaluation per clock.  Every flop of the design
//     is clocked on the rising edge and no logic looks at the clock level, so
//     the falling-edge evaluation changes nothing; the harness instead clears
//     the model's record of the last clock level, so the next evaluation sees
//     a rising edge;
//   TL_DIRECT_EVAL: call the generated evaluation step itself instead of
//     eval(), which adds a runtime wrapper per call (a mutex, a message queue
//     and thread-local look-ups, for threads and DPI this model has none of);
//   TL_SKIP_ICO: when no input changed since the last evaluation, skip the
//     input-combinational phase, whose only job is to propagate input changes
//     (logic that reads both inputs and state is also recomputed after the
//     edge).
// The last three use names Verilator generates but does not document
// (__Vtrigprevexpr___TOP__clk__0, ___eval, ___eval_phase__act/__nba); if a
// Verilator renames them this file stops compiling and native.py falls back
// to the public-API build.  The co-simulation test and bench_rtl_loop check
// that every build gives the same telemetry.
#include <cstdint>
#include <cstring>
#include <deque>
#include <vector>

#include "Vrtl_loop_top.h"
#include "Vrtl_loop_top___024root.h"
#include "verilated.h"

// Verilator's generated evaluation steps (not in its headers): the harness
// calls them directly, without the per-call runtime wrapper of eval().
void Vrtl_loop_top___024root___eval(Vrtl_loop_top___024root *vlSelf);
bool Vrtl_loop_top___024root___eval_phase__act(Vrtl_loop_top___024root *vlSelf);
bool Vrtl_loop_top___024root___eval_phase__nba(Vrtl_loop_top___024root *vlSelf);

namespace {

struct EncEdge {
    uint64_t cycle;
    uint8_t axis, a, b, z;
};

struct Harness {
    VerilatedContext ctx;
    Vrtl_loop_top *top = nullptr;
    uint64_t cycle = 0;
    std::deque<EncEdge> edges;
    uint8_t enc_a = 0, enc_b = 0, enc_z = 0;
    // host -> FPGA serialiser
    uint32_t div = 434;
    std::deque<uint8_t> txq;
    uint16_t tx_frame = 0;
    int tx_bits = 0;         // bits left in the frame being sent (0: idle)
    uint32_t tx_cnt = 0;
    // FPGA -> host deserialiser
    std::vector<uint8_t> rx;
    std::vector<uint64_t> rx_cycle;   // clock of each byte's start bit
    uint64_t rx_start = 0;
    int rx_bit = -1;         // -1 idle, 0..7 data, 8 stop
    uint32_t rx_cnt = 0;
    uint8_t rx_byte = 0;
    uint32_t rx_errors = 0;
    bool inputs_changed = true;   // an input differs from the last evaluation
};

uint8_t pins_of(const Vrtl_loop_top *t)
{
    // bit 4*axis + {0: RPWM, 1: LPWM, 2: R_EN, 3: L_EN}
    uint8_t p = 0;
    for (int ax = 0; ax < 2; ax++) {
        p |= ((t->rpwm >> ax) & 1) << (4 * ax);
        p |= ((t->lpwm >> ax) & 1) << (4 * ax + 1);
        p |= ((t->r_en >> ax) & 1) << (4 * ax + 2);
        p |= ((t->l_en >> ax) & 1) << (4 * ax + 3);
    }
    return p;
}

inline void host_line(Harness *h)
{
    if (h->tx_bits == 0 && !h->txq.empty()) {
        h->tx_frame = (uint16_t)((1u << 9) | ((uint32_t)h->txq.front() << 1));   // start 0, data, stop 1
        h->txq.pop_front();
        h->tx_bits = 10;
        h->tx_cnt = h->div;
    }
    uint8_t line = 1;
    if (h->tx_bits) {
        line = h->tx_frame & 1u;
        if (--h->tx_cnt == 0) {
            h->tx_frame >>= 1;
            h->tx_bits--;
            h->tx_cnt = h->div;
        }
    }
    if (line != h->top->host_tx) {
        h->top->host_tx = line;
        h->inputs_changed = true;
    }
}

inline void fpga_line(Harness *h)
{
    uint8_t v = h->top->host_rx & 1u;
    if (h->rx_bit < 0) {
        if (!v) {                       // start bit: sample the data bits mid-bit
            h->rx_bit = 0;
            h->rx_start = h->cycle;
            h->rx_cnt = h->div + h->div / 2;
            h->rx_byte = 0;
        }
        return;
    }
    if (--h->rx_cnt)
        return;
    if (h->rx_bit < 8) {
        h->rx_byte |= (uint8_t)(v << h->rx_bit);
        h->rx_bit++;
        h->rx_cnt = h->div;
    } else {
        if (v) {
            h->rx.push_back(h->rx_byte);
            h->rx_cycle.push_back(h->rx_start);
        }
        else
            h->rx_errors++;             // framing error: stop bit low
        h->rx_bit = -1;
    }
}

// Evaluate the model at a rising clock edge, with the inputs set before it.
inline void posedge(Harness *h)
{
    Vrtl_loop_top___024root *r = h->top->rootp;
#if TL_EVAL_PER_CLOCK == 2
    (void)r;
    h->top->clk = 1;
    h->top->eval();
    h->top->clk = 0;
    h->top->eval();
#else
    // The design has no logic on the falling edge: instead of evaluating it
    // there, tell the model the clock was low before this evaluation.
    h->top->clk = 1;
    r->__Vtrigprevexpr___TOP__clk__0 = 0;
#if TL_DIRECT_EVAL
#if TL_SKIP_ICO
    if (!h->inputs_changed) {
        // The input-combinational phase only propagates input changes (logic
        // that also reads state is recomputed after the edge anyway): with the
        // inputs as at the last evaluation, run the clocked phases alone.
        do {
            r->__VactIterCount = 0;
            while (Vrtl_loop_top___024root___eval_phase__act(r)) {
            }
        } while (Vrtl_loop_top___024root___eval_phase__nba(r));
        return;
    }
    h->inputs_changed = false;
#endif
    Vrtl_loop_top___024root___eval(r);
#else
    h->top->eval();
#endif
#endif
}

inline void tick(Harness *h)
{
    if (!h->edges.empty() && h->edges.front().cycle <= h->cycle) {
        do {
            const EncEdge &e = h->edges.front();
            uint8_t m = (uint8_t)(1u << e.axis);
            h->enc_a = (uint8_t)((h->enc_a & ~m) | (e.a << e.axis));
            h->enc_b = (uint8_t)((h->enc_b & ~m) | (e.b << e.axis));
            h->enc_z = (uint8_t)((h->enc_z & ~m) | (e.z << e.axis));
            h->edges.pop_front();
        } while (!h->edges.empty() && h->edges.front().cycle <= h->cycle);
        h->top->enc_a = h->enc_a;
        h->top->enc_b = h->enc_b;
        h->top->enc_z = h->enc_z;
        h->inputs_changed = true;
    }
    host_line(h);
    posedge(h);
    h->cycle++;
    fpga_line(h);
}

}  // namespace

extern "C" {

void *tl_create(void)
{
    Harness *h = new Harness;
    h->ctx.commandArgs(0, (const char **)nullptr);
    h->top = new Vrtl_loop_top(&h->ctx, "top");
    h->top->clk = 0;
    h->top->reset_n = 0;
    h->top->key0_n = 1;
    h->top->sw0 = 0;
    h->top->fault_n = 3;
    h->top->lim_neg = 0;   // limit switches closed: not at a limit
    h->top->lim_pos = 0;
    h->top->host_tx = 1;
    h->top->eval();
    return h;
}

void tl_destroy(void *p)
{
    Harness *h = static_cast<Harness *>(p);
    h->top->final();
    delete h->top;
    delete h;
}

void tl_set_board(void *p, int reset_n, int key0_n, int sw0, int fault_n)
{
    Harness *h = static_cast<Harness *>(p);
    h->top->reset_n = reset_n & 1;
    h->top->key0_n = key0_n & 1;
    h->top->sw0 = sw0 & 1;
    h->top->fault_n = fault_n & 3;
    h->inputs_changed = true;
}

// Limit switch pins, bit per axis, 1 = open (tripped).
void tl_set_limits(void *p, int neg, int pos)
{
    Harness *h = static_cast<Harness *>(p);
    h->top->lim_neg = neg & 3;
    h->top->lim_pos = pos & 3;
    h->inputs_changed = true;
}

void tl_set_uart_div(void *p, uint32_t clocks_per_bit) { static_cast<Harness *>(p)->div = clocks_per_bit; }

uint64_t tl_cycle(void *p) { return static_cast<Harness *>(p)->cycle; }

int tl_pins(void *p) { return pins_of(static_cast<Harness *>(p)->top); }

// Encoder edges, sorted by cycle, all at or after the present cycle.
void tl_push_edges(void *p, int n, const uint64_t *cycle, const uint8_t *axis, const uint8_t *a,
                   const uint8_t *b, const uint8_t *z)
{
    Harness *h = static_cast<Harness *>(p);
    for (int i = 0; i < n; i++)
        h->edges.push_back(EncEdge{cycle[i], axis[i], a[i], b[i], z[i]});
}

// Edges not applied yet are dropped (the plant was rolled back).
void tl_clear_edges(void *p) { static_cast<Harness *>(p)->edges.clear(); }

int tl_edges_pending(void *p) { return (int)static_cast<Harness *>(p)->edges.size(); }

// Encoder pin levels applied so far: bit axis of A, B, Z in bits 0-1, 2-3, 4-5.
int tl_enc_levels(void *p)
{
    Harness *h = static_cast<Harness *>(p);
    return h->enc_a | (h->enc_b << 2) | (h->enc_z << 4);
}

void tl_uart_send(void *p, int n, const uint8_t *data)
{
    Harness *h = static_cast<Harness *>(p);
    for (int i = 0; i < n; i++)
        h->txq.push_back(data[i]);
}

int tl_uart_tx_busy(void *p)
{
    Harness *h = static_cast<Harness *>(p);
    return !h->txq.empty() || h->tx_bits != 0;
}

// Bytes received from the FPGA since the last call (at most cap), with the
// clock of each byte's start bit.
int tl_uart_recv(void *p, int cap, uint8_t *out, uint64_t *cycles)
{
    Harness *h = static_cast<Harness *>(p);
    int n = (int)h->rx.size() < cap ? (int)h->rx.size() : cap;
    if (n) {
        std::memcpy(out, h->rx.data(), (size_t)n);
        std::memcpy(cycles, h->rx_cycle.data(), (size_t)n * sizeof(uint64_t));
        h->rx.erase(h->rx.begin(), h->rx.begin() + n);
        h->rx_cycle.erase(h->rx_cycle.begin(), h->rx_cycle.begin() + n);
    }
    return n;
}

uint32_t tl_uart_errors(void *p) { return static_cast<Harness *>(p)->rx_errors; }

// Run until cycle `until` (returns 0) or until a bridge pin changes
// (returns 1; the new levels hold from tl_cycle() on) when stop_on_pins.
int tl_run(void *p, uint64_t until, int stop_on_pins)
{
    Harness *h = static_cast<Harness *>(p);
    uint8_t before = pins_of(h->top);
    while (h->cycle < until) {
        tick(h);
        if (stop_on_pins && pins_of(h->top) != before)
            return 1;
    }
    return 0;
}

}  // extern "C"
