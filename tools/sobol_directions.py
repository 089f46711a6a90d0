"""Writes components/cpp/samplers/sobol_directions.h: the Sobol direction
numbers of Joe & Kuo (new-joe-kuo-6.21201, "Constructing Sobol sequences
with better two-dimensional projections", SIAM J. Sci. Comput. 30, 2008),
for all 21201 of its dimensions, from the copy scipy ships
(scipy/stats/_sobol_direction_numbers.npz, arrays `poly` and `vinit`).

Each dimension is stored as Joe & Kuo list it: its primitive polynomial
over GF(2) (all coefficients, the leading and constant 1 included) and its
initial direction numbers m_1 … m_s (s the polynomial's degree, m_k odd
and below 2^k). The sampler expands them to 32-bit direction numbers the
first time it is made. tests/test_sobol_directions.py checks that the
file is what this writes. Run from the repository with the venv's Python:

    .venv/bin/python tools/sobol_directions.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

OUT = (
    Path(__file__).resolve().parent.parent
    / "components"
    / "cpp"
    / "samplers"
    / "sobol_directions.h"
)
# All of them: integrands of up to 21201 variables, paths of any practical
# length.
DIMENSIONS = 21201


def header_text() -> str:
    """The header's text, from the direction numbers scipy ships."""
    import scipy
    import scipy.stats

    source = Path(scipy.stats.__file__).parent / "_sobol_direction_numbers.npz"
    data = np.load(source)
    poly, vinit = data["poly"], data["vinit"]
    rows = []
    max_degree = 0
    for j in range(DIMENSIONS):
        p = int(poly[j])
        degree = p.bit_length() - 1
        m = [int(v) for v in vinit[j, :degree]]
        if j == 0:
            # The first dimension is the van der Corput sequence, which the
            # file writes as the polynomial 1 with m_1 = 1 (the identity).
            assert p == 1 and vinit[0, 0] == 1
        else:
            assert all(v % 2 == 1 and v < (1 << (k + 1)) for k, v in enumerate(m)), j
            assert not vinit[j, degree:].any(), j
        max_degree = max(max_degree, degree)
        rows.append(f"    {{{p}, {{{', '.join(str(v) for v in m)}}}}},")
    return (
        '// Sobol direction numbers of Joe & Kuo (new-joe-kuo-6.21201; "Constructing\n'
        '// Sobol sequences with better two-dimensional projections", SIAM J. Sci.\n'
        f"// Comput. 30, 2008), all {DIMENSIONS} dimensions. Written by\n"
        "// tools/sobol_directions.py from scipy/stats/_sobol_direction_numbers.npz\n"
        f"// (scipy {scipy.__version__}); do not edit by hand.\n"
        "//\n"
        "// Row j: dimension j's primitive polynomial over GF(2), all coefficients\n"
        "// as bits (x^s + a_1 x^(s-1) + … + 1), and its initial direction numbers\n"
        "// m_1 … m_s. Row 0, the polynomial 1, is the van der Corput sequence.\n"
        "#pragma once\n\n"
        "#include <cstdint>\n\n"
        "namespace yarf::sobol {\n\n"
        f"inline constexpr uint32_t kDimensions = {DIMENSIONS};\n"
        f"inline constexpr int kMaxDegree = {max_degree};\n\n"
        "struct Primitive {\n"
        "  uint32_t polynomial;\n"
        "  uint32_t m[kMaxDegree];\n"
        "};\n\n"
        "inline constexpr Primitive kPrimitives[kDimensions] = {\n" + "\n".join(rows) + "\n};\n\n"
        "}  // namespace yarf::sobol\n"
    )


def main() -> None:
    OUT.write_text(header_text())


if __name__ == "__main__":
    main()
