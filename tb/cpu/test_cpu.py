# SPDX-License-Identifier: MIT
"""CPU core (rtl/cpu) against the ISS oracle (torqueloop/oracles/rv32.py).

Every program is compiled at test time, run on cpu_sim_top and on the ISS,
and the two must agree on the tohost value and on every signature word
(registers and memory the program dumps).  Interrupt programs cannot run on
the ISS (it has no timer); they check themselves and report through tohost,
and the test bench measures interrupt latency from the outside.

Environment (set by the pytest entry per simulator):
  CPU_RANDOM_PROGS   number of random programs      CPU_RANDOM_LEN  instructions each
"""

from __future__ import annotations

import os
import random

import cocotb
import pytest
from cocotb.triggers import ReadOnly, RisingEdge

import randprog
from cpu_progs import BUILD, PROGS, build, run_iss
from cpu_tb import CpuTb
from torqueloop.oracles.rv32 import read_elf
from torqueloop.flow.cpu_progs import CPU_CORES as CORES
from torqueloop.flow.simrun import run, sims_for

TAG = os.environ.get("CPU_PROG_TAG", "default")


async def check_against_iss(tb: CpuTb, elf_path, wait_states: bool = False, max_cycles: int = 2_000_000):
    elf = read_elf(elf_path)
    ref = run_iss(elf_path)
    await tb.load(elf, wait_states=wait_states)
    res = await tb.run(max_cycles)
    assert res.tohost is not None, f"{elf_path.name}: no tohost write within {max_cycles} cycles"
    assert res.tohost == ref.tohost, f"{elf_path.name}: tohost {res.tohost:#x}, ISS {ref.tohost:#x}"
    sig = await tb.signature(elf)
    bad = [(i, s, r) for i, (s, r) in enumerate(zip(sig, ref.signature)) if s != r]
    assert not bad, (f"{elf_path.name}: {len(bad)} signature words differ, first: word {bad[0][0]} "
                     f"core {bad[0][1]:#010x} ISS {bad[0][2]:#010x}")
    # the boot stub (lui + jalr) retires two instructions the ISS does not run
    assert res.instret == ref.instructions + 2, f"{elf_path.name}: instret {res.instret} vs ISS {ref.instructions}+2"
    return res


@cocotb.test()
async def random_streams_match_iss(dut):
    """Seeded random RV32IM streams, register and memory state compared with the ISS."""
    tb = CpuTb(dut)
    n_progs = int(os.environ.get("CPU_RANDOM_PROGS", "2"))
    length = int(os.environ.get("CPU_RANDOM_LEN", "300"))
    for k in range(n_progs):
        seed = random.getrandbits(32)
        dut._log.info("random program %d: seed %d (%d instructions), wait states %s",
                      k, seed, length, bool(k & 1))
        src = BUILD / TAG / f"rand_{seed}.S"
        src.parent.mkdir(parents=True, exist_ok=True)
        src.write_text(randprog.generate(seed, length))
        elf = build(f"rand_{seed}", [src], tag=TAG, crt0=False)
        res = await check_against_iss(tb, elf, wait_states=bool(k & 1))
        dut._log.info("  %d cycles, %d instructions, CPI %.2f", res.cycles, res.instret, res.cycles / res.instret)


#: directed programs: name -> (sources, linked with crt0)
DIRECTED = {
    "traps": (["traps.S"], False),
    "muldiv_corners": (["muldiv_corners.S"], False),
    "div_widths": (["div_widths.S"], False),
    "bench": (["bench.c"], True),
    "cstress": (["cstress.c"], True),
    "selfmod": (["selfmod.S"], False),
}


@cocotb.test()
async def directed_programs_match_iss(dut):
    """Exceptions/CSRs, M-extension corner cases and compiled C, against the ISS."""
    tb = CpuTb(dut)
    names = os.environ.get("CPU_DIRECTED", ",".join(DIRECTED)).split(",")
    for k, name in enumerate(names):
        srcs, crt0 = DIRECTED[name]
        elf = build(name, [PROGS / s for s in srcs], tag=TAG, crt0=crt0)
        res = await check_against_iss(tb, elf, wait_states=bool(k & 1))
        dut._log.info("%s: %d cycles, %d instructions, CPI %.2f (wait states %s)", name, res.cycles,
                      res.instret, res.cycles / res.instret, bool(k & 1))


MTI, MEI, MSI = 0x8000_0007, 0x8000_000B, 0x8000_0003
S_MULDIV = 3  # tl_cpu's state encoding, for classifying when an interrupt arrived


def in_muldiv(dut) -> bool:
    """A multiply/divide is in progress in the core under test."""
    if int(dut.PIPELINED.value):
        return int(dut.g_pipe.u_cpu.in_md.value) == 1
    return int(dut.g_multi.u_cpu.state.value) == S_MULDIV


@cocotb.test()
async def interrupts_latency_nesting_and_divide(dut):
    """Timer/external/software interrupts: order, masking, nesting, latency, during divides."""
    tb = CpuTb(dut)
    elf_path = build("irq", [PROGS / "irq.S"], tag=TAG, crt0=False)
    elf = read_elf(elf_path)
    handler = elf.symbols["handler"]
    await tb.load(elf)

    samples: list[tuple[int, bool]] = []  # (cycles from irq_timer rising to handler fetch, arrived in a divide)

    async def monitor() -> None:
        while True:
            await RisingEdge(dut.irq_timer)
            await ReadOnly()
            in_div = in_muldiv(dut)
            for n in range(200):
                if int(dut.ibus_req.value) and int(dut.ibus_addr.value) == handler:
                    samples.append((n, in_div))
                    break
                await RisingEdge(dut.clk)
                await ReadOnly()

    mon = cocotb.start_soon(monitor())
    res = await tb.run(200_000)
    mon.cancel()
    assert res.tohost is not None, "irq program did not finish"
    assert res.tohost == 1, f"irq program failed check {res.tohost >> 1}"
    words = await tb.signature(elf)
    count, log = words[0], words[1:1 + words[0]]
    expected_prefix = [MTI] * 4 + [MTI] + [MTI, MEI] + [MEI, MSI, MTI]
    assert log[:len(expected_prefix)] == expected_prefix, f"trap order {[hex(c) for c in log[:10]]}"
    assert all(c == MTI for c in log[len(expected_prefix):]), "unexpected trap during the divide loop"
    spin = [n for n, _ in samples[:4]]
    in_div = [n for n, d in samples if d]
    dut._log.info("timer interrupt latency from a spin loop: %s cycles (irq_timer high -> handler fetch request)", spin)
    dut._log.info("%d of %d timer interrupts arrived during a divide; latency max %s cycles",
                  len(in_div), len(samples), max(in_div) if in_div else None)
    assert max(spin) <= 6, f"spin-loop latency {spin}"
    assert len(in_div) >= 5, "too few interrupts landed in a divide to test that case"
    # a divide in progress is abandoned for the interrupt: no 34-cycle wait
    assert max(in_div) <= 3, f"latency in a divide {max(in_div)}"
    dut._log.info("%d traps logged, %d cycles", count, res.cycles)




@pytest.mark.parametrize("core", list(CORES))
@pytest.mark.parametrize("sim", sims_for("cpu_sim_top", langs=("verilog",)))
def test_cpu(sim, core):
    env = {"CPU_PROG_TAG": f"{sim}-{core}"}
    if sim == "icarus":
        env.update(CPU_RANDOM_PROGS="2", CPU_RANDOM_LEN="300", CPU_DIRECTED="traps,muldiv_corners,selfmod")
    else:
        env.update(CPU_RANDOM_PROGS="12", CPU_RANDOM_LEN="3000")
    run("cpu_sim_top", sim, "test_cpu", parameters=CORES[core], extra_env=env)
