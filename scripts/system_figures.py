"""The figures of docs/systems.md: each worked example's schematic and motion, drawn by the package
from the system files in docs/systems/ (``python scripts/system_figures.py``)."""

from __future__ import annotations

from pathlib import Path

import oscillator

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    for name in ("blade-damper", "conveyor", "belt-chain"):
        chain = oscillator.load_system(ROOT / "docs" / "systems" / f"{name}.toml")
        chain.plot().savefig(ROOT / "docs" / "images" / f"system-{name}-schematic.png", dpi=90, bbox_inches="tight")
        result = oscillator.simulate_chain(chain)
        result.plot().savefig(ROOT / "docs" / "images" / f"system-{name}-motion.png", dpi=80, bbox_inches="tight")
        print(name, len(result.events), "events", f"energy residual {result.energy.residual:.1e} J")


if __name__ == "__main__":
    main()
