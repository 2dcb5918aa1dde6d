/* SPDX-License-Identifier: MIT */
/* The uploaded program of the bootloader bench: shows APP_LEDS, says "APP\n",
 * and on a received 'B' hands back to the bootloader the documented way
 * (docs/bootloader.md: jump to TL_BOOT_ROM_BASE), as the servo firmware's
 * BOOTLOADER command does. */
#include <stdint.h>

#include "torqueloop_regs.h"

#define APP_LEDS 0x2A5u

static void put(char c)
{
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK)) {
    }
    TL_UART_TX_DATA = (uint8_t)c;
}

int main(void)
{
    TL_GPIO_LEDR = APP_LEDS;
    put('A');
    put('P');
    put('P');
    put('\n');
    for (;;) {
        uint32_t r = TL_UART_RX_DATA;
        if ((r & TL_UART_RX_DATA_VALID_MSK) && (r & 0xFFu) == 'B') {
            while (!(TL_UART_STATUS & TL_UART_STATUS_TX_IDLE_MSK)) {
            }
            __asm__ volatile("csrci mstatus, 8");
            void (*boot)(void) = (void (*)(void))(uintptr_t)TL_BOOT_ROM_BASE;
            boot();
        }
    }
}
