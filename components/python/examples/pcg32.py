"""py_pcg32: O'Neill's PCG-XSH-RR 64/32, as a Python Generator (the numbers of yarfd's pcg32).

A 64-bit LCG whose 32-bit outputs are the old state's high bits
xor-shifted down and rotated by its top five bits; a number in [0, 1) is
the output's top 24 bits times 2^-24. Seeding is the reference
pcg32_srandom: ``seed`` is the initial state, ``stream`` selects the
increment 2·stream + 1. Skipping ``offset`` outputs costs O(log offset)
(the LCG's n-step map by squaring, as pcg32_advance). Stateless between
calls. No properties.
"""

from __future__ import annotations

import numpy as np

from yarf_component import Generator

MASK = (1 << 64) - 1
MULTIPLIER = 6364136223846793005


def step(state: int, increment: int) -> int:
    return (state * MULTIPLIER + increment) & MASK


def output(state: int) -> int:
    shifted = (((state >> 18) ^ state) >> 27) & 0xFFFFFFFF
    rotation = state >> 59
    return ((shifted >> rotation) | (shifted << (-rotation & 31))) & 0xFFFFFFFF


def advance(state: int, increment: int, steps: int) -> int:
    total_multiplier, total_increment = 1, 0
    multiplier, step_increment = MULTIPLIER, increment
    while steps > 0:
        if steps & 1:
            total_multiplier = (total_multiplier * multiplier) & MASK
            total_increment = (total_increment * multiplier + step_increment) & MASK
        step_increment = (step_increment * (multiplier + 1)) & MASK
        multiplier = (multiplier * multiplier) & MASK
        steps >>= 1
    return (total_multiplier * state + total_increment) & MASK


class Pcg32(Generator):
    class_name = "py_pcg32"
    summary = "O'Neill's PCG-XSH-RR 64/32 with stream selection and O(log n) advance"

    def next(self, seed: int, stream: int, offset: int, count: int) -> np.ndarray:
        increment = ((stream << 1) | 1) & MASK
        state = step((step(0, increment) + seed) & MASK, increment)
        state = advance(state, increment, offset)
        bits = np.empty(count, np.uint32)
        for i in range(count):
            bits[i] = output(state)
            state = step(state, increment)
        return (bits >> 8).astype(np.float32) * np.float32(2.0**-24)
