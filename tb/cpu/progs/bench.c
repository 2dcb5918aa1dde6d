/* SPDX-License-Identifier: MIT */
// Small integer benchmark and C-level test: CRC-32 of a pseudo-random
// buffer, a sort of 256 words, a 12x12 matrix product and integer
// formatting (division by 10).  Results go into the signature, which the
// test compares with the ISS; run_elf.py and bench_cpu.py report its CPI.
#include <stdint.h>

#define BUF_BYTES 1024u
#define SORT_N 256u
#define MAT_N 12u

__attribute__((section(".signature"))) volatile uint32_t sig[16];

static uint8_t buf[BUF_BYTES];
static int32_t arr[SORT_N];
static int16_t ma[MAT_N][MAT_N], mb[MAT_N][MAT_N];
static int32_t mc[MAT_N][MAT_N];

static uint32_t lcg(uint32_t *s) {
    *s = *s * 1664525u + 1013904223u;
    return *s;
}

static uint32_t crc32(const uint8_t *p, uint32_t n) {
    uint32_t crc = 0xFFFFFFFFu;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

static void sort(int32_t *a, uint32_t n) {  // insertion sort
    for (uint32_t i = 1; i < n; i++) {
        int32_t v = a[i];
        uint32_t j = i;
        while (j > 0 && a[j - 1] > v) {
            a[j] = a[j - 1];
            j--;
        }
        a[j] = v;
    }
}

static uint32_t format_sum(int32_t v) {  // decimal digits via / and %
    char out[12];
    uint32_t n = 0, sum = 0;
    uint32_t u = v < 0 ? (uint32_t)(-(int64_t)v) : (uint32_t)v;
    do {
        out[n++] = (char)('0' + u % 10u);
        u /= 10u;
    } while (u);
    for (uint32_t i = 0; i < n; i++)
        sum = sum * 31u + (uint32_t)out[i];
    return sum + (v < 0);
}

int main(void) {
    uint32_t s = 12345u;
    for (uint32_t i = 0; i < BUF_BYTES; i++)
        buf[i] = (uint8_t)(lcg(&s) >> 24);
    sig[0] = crc32(buf, BUF_BYTES);

    for (uint32_t i = 0; i < SORT_N; i++)
        arr[i] = (int32_t)lcg(&s) >> 8;
    sort(arr, SORT_N);
    uint32_t sorted = 1, h = 0;
    for (uint32_t i = 0; i < SORT_N; i++) {
        if (i && arr[i - 1] > arr[i])
            sorted = 0;
        h = h * 33u ^ (uint32_t)arr[i];
    }
    sig[1] = h;
    sig[2] = sorted;

    for (uint32_t i = 0; i < MAT_N; i++)
        for (uint32_t j = 0; j < MAT_N; j++) {
            ma[i][j] = (int16_t)(lcg(&s) >> 16);
            mb[i][j] = (int16_t)(lcg(&s) >> 16);
        }
    int64_t trace = 0;
    for (uint32_t i = 0; i < MAT_N; i++)
        for (uint32_t j = 0; j < MAT_N; j++) {
            int32_t acc = 0;
            for (uint32_t k = 0; k < MAT_N; k++)
                acc += ma[i][k] * mb[k][j];
            mc[i][j] = acc;
        }
    for (uint32_t i = 0; i < MAT_N; i++)
        trace += (int64_t)mc[i][i] * mc[i][(i + 1) % MAT_N];
    sig[3] = (uint32_t)trace;
    sig[4] = (uint32_t)(trace >> 32);

    uint32_t fs = 0;
    for (uint32_t i = 0; i < 64; i++)
        fs += format_sum((int32_t)lcg(&s) / (int32_t)(i + 1));
    sig[5] = fs;
    return sorted ? 0 : 2;
}
