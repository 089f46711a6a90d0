"""Writes server/include/yarf/support/named_metals.h: the complex indices of
refraction of the metals Mitsuba 3 names (its data/ior spectra, measured by
Palik and others), as Mitsuba's RGB variants see them.

Mitsuba converts each spectrum of η and κ to linear sRGB itself when a
conductor names its `material`; this reads those values back through
Mitsuba's own Python module, so yarf's conductors match Mitsuba's RGB
renders. Run from the repository with the venv's Python:

    .venv/bin/python tools/named_metals.py
"""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
OUT = REPO / "server" / "include" / "yarf" / "support" / "named_metals.h"
# A channel with η = κ = 0 (an out-of-gamut colour clamped) has no
# Fresnel factor: its κ is raised to this.
SMALLEST_K = 1e-4


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    folder = Path(mi.__file__).parent / "data" / "ior"
    names = sorted({path.name.split(".")[0] for path in folder.glob("*.eta.spd")})
    rows = []
    for name in names:
        params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
        eta = [float(v) for v in params["eta.value"]]
        k = [float(v) for v in params["k.value"]]
        k = [
            max(kc, SMALLEST_K) if ec == 0 and kc == 0 else kc
            for ec, kc in zip(eta, k, strict=True)
        ]

        def number(v: float) -> str:
            text = f"{v:.6g}"
            return (text if "." in text or "e" in text else text + ".0") + "f"

        def triple(values: list[float]) -> str:
            return "{" + ", ".join(number(v) for v in values) + "}"

        rows.append(f'    {{"{name}", {{{triple(eta)}, {triple(k)}}}}},')
    OUT.write_text(
        "// The metals conductors may name ('material'): complex indices of\n"
        "// refraction η + iκ in linear sRGB, as Mitsuba 3's RGB variants convert\n"
        "// the spectra it ships (data/ior). Written by tools/named_metals.py from\n"
        f"// Mitsuba {mi.__version__}; do not edit by hand.\n"
        "#pragma once\n\n"
        "#include <string_view>\n\n"
        '#include "yarf/vecmath.h"\n\n'
        "namespace yarf::metals {\n\n"
        "struct ComplexIor {\n  Vec3 eta, k;\n};\n\n"
        "struct NamedMetal {\n  const char* name;\n  ComplexIor ior;\n};\n\n"
        "inline constexpr NamedMetal kMetals[] = {\n" + "\n".join(rows) + "\n};\n\n"
        "inline bool IsNamed(std::string_view name) {\n"
        "  for (const NamedMetal& metal : kMetals)\n"
        "    if (name == metal.name) return true;\n"
        "  return false;\n}\n\n"
        "}  // namespace yarf::metals\n"
    )


if __name__ == "__main__":
    main()
