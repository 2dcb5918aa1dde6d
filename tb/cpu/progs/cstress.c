/* SPDX-License-Identifier: MIT */
// Compiled-code coverage beyond bench.c: recursion, a switch compiled to a
// jump table (JALR through a loaded address), byte/halfword struct fields,
// 64-bit division and remainder from libgcc, signed/unsigned conversions and
// function pointers.  Results go into the signature (compared with the ISS).
#include <stdint.h>

__attribute__((section(".signature"))) volatile uint32_t sig[24];

struct rec {
    uint8_t a;
    int8_t b;
    int16_t c;
    uint16_t d;
    uint32_t e;
};

static struct rec recs[32];

static uint32_t fib(uint32_t n) { return n < 2 ? n : fib(n - 1) + fib(n - 2); }

static __attribute__((noinline)) int32_t classify(uint32_t k, int32_t x) {
    switch (k & 15) {
    case 0: return x + 1;
    case 1: return x * 3;
    case 2: return x >> 2;
    case 3: return (int32_t)((uint32_t)x >> 3);
    case 4: return -x;
    case 5: return x ^ 0x5a5a;
    case 6: return x / 7;
    case 7: return x % 11;
    case 8: return x < 0;
    case 9: return (int32_t)(int8_t)x;
    case 10: return (int32_t)(int16_t)x;
    case 11: return (int32_t)(uint8_t)x;
    default: return x & 0xff0;
    }
}

static int32_t add3(int32_t x) { return x + 3; }
static int32_t sub5(int32_t x) { return x - 5; }
static int32_t (*const ops[2])(int32_t) = {add3, sub5};

int main(void) {
    uint32_t s = 0x1234567u;
    for (uint32_t i = 0; i < 32; i++) {
        s = s * 1103515245u + 12345u;
        recs[i].a = (uint8_t)s;
        recs[i].b = (int8_t)(s >> 8);
        recs[i].c = (int16_t)(s >> 12);
        recs[i].d = (uint16_t)(s >> 5);
        recs[i].e = s;
    }
    int32_t acc = 0;
    uint32_t uacc = 0;
    for (uint32_t i = 0; i < 32; i++) {
        acc += recs[i].b * recs[i].c;
        uacc += recs[i].a * recs[i].d;
        recs[i].c = (int16_t)(recs[i].c - recs[i].b);
        recs[i].a ^= (uint8_t)i;
    }
    sig[0] = (uint32_t)acc;
    sig[1] = uacc;
    sig[2] = recs[7].a | (uint32_t)recs[9].c << 8;
    sig[3] = fib(18);

    int32_t x = -123456789;
    for (uint32_t k = 0; k < 64; k++)
        x = classify(k, x) + (int32_t)(k * 2654435761u);
    sig[4] = (uint32_t)x;

    uint64_t big = 0xfedcba9876543210ull;
    int64_t sbig = -0x123456789abcdefll;
    sig[5] = (uint32_t)(big / 1000003u);
    sig[6] = (uint32_t)((big / 1000003u) >> 32);
    sig[7] = (uint32_t)(big % 999983u);
    sig[8] = (uint32_t)(sbig / 77777);
    sig[9] = (uint32_t)((uint64_t)(sbig / 77777) >> 32);
    sig[10] = (uint32_t)(sbig % 77777);
    sig[11] = (uint32_t)((big * 0x9e3779b97f4a7c15ull) >> 17);

    int32_t y = 1000;
    for (uint32_t i = 0; i < 10; i++)
        y = ops[i & 1](y) * 2;
    sig[12] = (uint32_t)y;
    return fib(10) == 55 ? 0 : 1;
}
