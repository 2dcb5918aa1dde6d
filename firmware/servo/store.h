/* SPDX-License-Identifier: MIT */
/* The parameter store (SAVE, docs/firmware.md "Settings that survive"): two
 * copies of the running parameters in two sectors of the configuration flash,
 * the record and the flash facts of protocol.toml's [store]. */
#ifndef TL_STORE_H
#define TL_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "servo.h"

typedef struct {
    bool saved;       /* a valid copy is stored */
    bool differs;     /* the running parameters are not the ones it holds */
    uint32_t seq;     /* its sequence number */
} tl_store_report_t;

/* At start-up, before the parameters are used: the newest valid copy, if any,
 * over the defaults (entries unknown to this firmware or out of range skipped). */
void tl_store_load(tl_servo_t *s);
/* SAVE op 1: a new copy of the running parameters (every axis disabled); a TLP_ST_* status,
 * a refusal's rule in *why. */
uint8_t tl_store_save(tl_servo_t *s, uint8_t *why);
void tl_store_report(const tl_servo_t *s, tl_store_report_t *r);
/* The SAVE command: op, and the reply's fields after the status; returns the status. */
uint8_t tl_store_command(tl_servo_t *s, uint8_t op, uint8_t *rep, uint8_t *why);

#endif
