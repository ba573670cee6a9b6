"""Cortex-M3 cycles of an executed instruction sequence, from the instruction timings of the Cortex-M3
Technical Reference Manual (ARM DDI 0337, "Instruction timings"): an estimate, for ``bench/bench_firmware.py``.

QEMU counts instructions, not cycles: on its Cortex-M3 machines the DWT cycle counter reads 0, and with
``-icount`` its clocks advance per instruction. So each instruction of a QEMU trace (the program counters
in order, ``cross.trace_steps``) is given the TRM's cycles for its kind, from the program's disassembly:

- data processing, MUL: 1; MLA, MLS: 2; long multiplies 3-5 and divides 2-12 (early termination on the
  operands): their upper bounds, 5 and 12;
- a single load or store: 2, or 1 right after another (the TRM: neighbouring single loads and stores
  pipeline); LDRD, STRD, LDM, STM, PUSH, POP: 1 + registers;
- a branch taken (the next instruction is not the following one), or a load or POP into pc: 1 + P more, P = 2
  for the pipeline refill (the TRM: 1-3, by alignment and width of the target); not taken: 1.

Flash wait states (the STM32F103 at 72 MHz: 2) are modelled where the prefetch buffer cannot hide them:
each taken branch and each load from flash (a pc-relative literal) waits that much more. Interrupts,
bus contention and the prefetch buffer's misses on long sequential runs are not modelled.
"""

from __future__ import annotations

import dataclasses
import re
import subprocess
from pathlib import Path

PIPELINE_REFILL_CYCLES = 2  # P of the TRM (1-3)
STM32F103_72MHZ_WAIT_STATES = 2  # flash latency the reference manual prescribes for 48-72 MHz

_CONDITIONS = {"eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le", "al"}
_LINE = re.compile(r"^\s*([0-9a-f]+):\s+((?:[0-9a-f]{4} ?){1,2})\s+(\S+)\s*(.*)$")


@dataclasses.dataclass(frozen=True)
class Instruction:
    mnemonic: str  # without .n/.w, condition suffix kept (beq, moveq)
    operands: str
    size: int  # bytes


def disassemble(elf: Path) -> dict[int, Instruction]:
    """Address -> instruction, from ``arm-none-eabi-objdump -d`` (Thumb)."""
    out = subprocess.run(["arm-none-eabi-objdump", "-d", str(elf)], capture_output=True, text=True, check=True).stdout
    program = {}
    for line in out.splitlines():
        match = _LINE.match(line)
        if match and not match.group(3).startswith("."):  # .word: a literal, not an instruction
            address, raw, mnemonic, operands = match.groups()
            program[int(address, 16)] = Instruction(mnemonic.split(".")[0], operands.split("@")[0].strip(), len(raw.split()) * 2)
    return program


def _is_branch(m: str) -> bool:
    if m in {"b", "bl", "bx", "blx", "cbz", "cbnz"}:
        return True
    return m.startswith("b") and (m[1:] in _CONDITIONS or (m[:2] in {"bx", "bl"} and m[2:] in _CONDITIONS))


def _registers(operands: str) -> list[str]:
    inside = operands[operands.index("{") + 1 : operands.index("}")]
    names = []
    for part in (p.strip() for p in inside.split(",")):
        if "-" in part:
            first, last = (int(r.strip()[1:]) for r in part.split("-"))
            names += [f"r{i}" for i in range(first, last + 1)]
        else:
            names.append(part)
    return names


def _base(m: str) -> str:
    """The mnemonic without a condition suffix (moveq -> mov; an IT block's instructions carry one)."""
    return m[:-2] if len(m) > 3 and m[-2:] in _CONDITIONS else m


def cycles(program: dict[int, Instruction], pcs: list[int], wait_states: int = 0) -> int:
    """Cycles of executing the instructions at ``pcs`` in that order (the last one's successor unknown:
    counted as not branching)."""
    total, previous_single = 0, False
    for i, pc in enumerate(pcs):
        ins = program[pc]
        m, ops = ins.mnemonic, ins.operands
        base = _base(m)
        taken = i + 1 < len(pcs) and pcs[i + 1] != pc + ins.size
        single = False
        if _is_branch(m):
            cost = 1 + (PIPELINE_REFILL_CYCLES + wait_states if taken else 0)
        elif m.startswith(("push", "pop", "ldm", "stm")):
            cost = 1 + len(_registers(ops))
            if taken:  # pop {..., pc} / ldm into pc: a return
                cost += PIPELINE_REFILL_CYCLES + wait_states
        elif base in {"ldrd", "strd"}:
            cost = 3
        elif base.startswith(("ldr", "str")):
            single = True
            cost = 1 if previous_single else 2
            if "[pc" in ops:  # a literal in flash
                cost += wait_states
            if taken:  # ldr pc, ...
                cost += PIPELINE_REFILL_CYCLES + wait_states
        elif base in {"umull", "smull", "umlal", "smlal"}:
            cost = 5
        elif base in {"udiv", "sdiv"}:
            cost = 12
        elif base in {"mla", "mls"}:
            cost = 2
        else:
            cost = 1 + (PIPELINE_REFILL_CYCLES + wait_states if taken else 0)  # taken: an instruction writing pc
        total += cost
        previous_single = single
    return total
