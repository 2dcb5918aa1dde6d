/* SPDX-License-Identifier: MIT */
/* Board-top test program: the configuration flash through the board top's
 * flash block (rtl/board/tl_config_flash.v), with the EPCS commands the
 * parameter store uses (firmware/servo/store.c; opcodes from protocol.toml).
 *
 * Each result goes out of the header UART (1 Mbaud) as it comes:
 *   1. READ 4 bytes at the store's first slot (what the flash held);
 *   2. WRITE ENABLE, then READ STATUS (WEL must be set);
 *   3. PAGE PROGRAM 4 bytes there, READ STATUS until WIP clears, the number
 *      of polls (one byte, at most 255);
 *   4. READ 4 bytes back.
 * Then it waits for ever.  It runs from the boot ROM, arms nothing.
 */
#include <stdint.h>

#include "torqueloop_regs.h"
#include "../../../firmware/protocol/tl_protocol.h"

static uint8_t xfer(uint8_t out)
{
    TL_FLASH_TX = out;
    uint32_t rx;
    while ((rx = TL_FLASH_RX) & TL_FLASH_RX_BUSY_MSK) {
    }
    return (uint8_t)(rx & TL_FLASH_RX_DATA_MSK);
}

static void select(int on) { TL_FLASH_CTRL = on ? TL_FLASH_CTRL_CS_MSK : 0u; }

static void send(uint8_t b)
{
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK)) {
    }
    TL_UART_TX_DATA = b;
}

static void command(uint8_t op, uint32_t addr)
{
    select(1);
    xfer(op);
    xfer((uint8_t)(addr >> 16));
    xfer((uint8_t)(addr >> 8));
    xfer((uint8_t)addr);
}

static uint8_t status(void)
{
    select(1);
    xfer(TLP_STORE_OP_READ_STATUS);
    uint8_t st = xfer(0xFFu);
    select(0);
    return st;
}

static void read_and_send(uint32_t addr)
{
    command(TLP_STORE_OP_READ, addr);
    for (int i = 0; i < 4; i++)
        send(xfer(0xFFu));
    select(0);
}

int main(void)
{
    static const uint8_t word[4] = {0x54u, 0x4Cu, 0x21u, 0x0Fu};
    TL_UART_BAUD_DIV = 49u;                       /* 1 Mbaud: 50 clocks per bit */
    read_and_send(TLP_STORE_SLOT_A);
    select(1);
    xfer(TLP_STORE_OP_WRITE_ENABLE);
    select(0);
    send(status());
    command(TLP_STORE_OP_PAGE_PROGRAM, TLP_STORE_SLOT_A);
    for (int i = 0; i < 4; i++)
        xfer(word[i]);
    select(0);
    uint32_t polls = 0;
    while ((status() & TLP_STORE_STATUS_WIP) && polls < 255u)
        polls++;
    send((uint8_t)polls);
    read_and_send(TLP_STORE_SLOT_A);
    for (;;) {
    }
}
