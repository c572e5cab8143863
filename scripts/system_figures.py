"""The figures of docs/systems.md: each worked example's schematic and motion, and the friction
damper's sweeps up and down (as ``oscillator frc`` draws them), drawn by the package from the system
files in docs/systems/ (``python scripts/system_figures.py``)."""

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
    import numpy as np
    import pandas as pd

    from oscillator.report.chain_frequency import sweep_figure

    chain = oscillator.load_system(ROOT / "docs" / "systems" / "blade-damper.toml")
    band = np.linspace(0.6, 1.6, 21)
    up = oscillator.frequency_sweep(chain, band).assign(direction="up")
    down = oscillator.frequency_sweep(chain, band[::-1]).assign(direction="down")
    figure = sweep_figure(pd.concat([up, down], ignore_index=True), chain, "Omega")
    figure.savefig(ROOT / "docs" / "images" / "system-blade-damper-frc.png", dpi=80, bbox_inches="tight")


if __name__ == "__main__":
    main()
