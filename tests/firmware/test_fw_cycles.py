"""The Cortex-M3 cycle estimate of bench_firmware (firmware_protocol/reference/cycles.py) applies the TRM's
instruction timings: a hand-counted sequence."""

from firmware_protocol.reference.cycles import Instruction, cycles

PROGRAM = {
    0x100: Instruction("ldr", "r0, [pc, #8]", 2),  # a literal in flash: 2, plus the wait states
    0x102: Instruction("ldr", "r1, [r0, #0]", 2),  # right after a load: pipelined, 1
    0x104: Instruction("cmp", "r0, r1", 2),  # 1
    0x106: Instruction("beq", "110 <f+0x10>", 2),  # taken: 1 + P (2), plus the wait states
    0x110: Instruction("umull", "r0, r1, r2, r3", 4),  # long multiply: its upper bound, 5
    0x114: Instruction("pop", "{r4, r5, pc}", 2),  # 1 + 3 registers, a return: + P, plus the wait states
    0x200: Instruction("moveq", "r0, #1", 2),  # in an IT block, condition false or not: 1
    0x202: Instruction("bne", "208 <g+0x8>", 2),  # not taken: 1
    0x204: Instruction("strd", "r0, r1, [sp]", 4),  # 1 + 2 registers
}
PCS = [0x100, 0x102, 0x104, 0x106, 0x110, 0x114, 0x200, 0x202, 0x204]


def test_a_hand_counted_sequence_without_and_with_flash_wait_states():
    assert cycles(PROGRAM, PCS) == 2 + 1 + 1 + 3 + 5 + 6 + 1 + 1 + 3
    assert cycles(PROGRAM, PCS, wait_states=2) == cycles(PROGRAM, PCS) + 3 * 2
