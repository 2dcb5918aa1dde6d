/* SPDX-License-Identifier: MIT */
/* Stand-in factory firmware for the bootloader bench (RAM-linked with
 * firmware/common/crt0.S + link.ld, like the servo firmware).  It proves it
 * started from a pristine copy: an initialised .data word and a .bss word are
 * checked before they are changed, so an image left dirty by an earlier run
 * (no fresh copy from ROM) shows on the LEDs. */
#include <stdint.h>

#include "torqueloop_regs.h"

#define FACTORY_LEDS 0x0F0u
#define DIRTY_LEDS 0x3FFu

static volatile uint32_t data_word = 0x5EED1234u;
static volatile uint32_t bss_word;

static void put(char c)
{
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK)) {
    }
    TL_UART_TX_DATA = (uint8_t)c;
}

int main(void)
{
    int pristine = data_word == 0x5EED1234u && bss_word == 0u;
    data_word = 0u;
    bss_word = 0xFFFFFFFFu;
    TL_GPIO_LEDR = pristine ? FACTORY_LEDS : DIRTY_LEDS;
    put('F');
    put('A');
    put('C');
    put('\n');
    for (;;) {
        (void)TL_UART_RX_DATA;   /* swallow whatever arrives, as a link parser would */
    }
}
