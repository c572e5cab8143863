"""The figures of docs/systems.md and docs/damper-design.md: each worked example's schematic and
motion, the friction damper's sweeps up and down (as ``oscillator frc`` draws them) and its design
over the normal load, drawn by the package from the system files in docs/systems/
(``python scripts/system_figures.py``, or ``python scripts/system_figures.py design`` for the
design's figure alone)."""

from __future__ import annotations

import sys
from pathlib import Path

import oscillator

ROOT = Path(__file__).resolve().parents[1]


def damper_design() -> None:
    """docs/damper-design.md's figure: the worst blade amplitude over the band against the
    slider's strength (the design's values and a grid from no friction to a stuck damper), and
    the sweeps at the grid's ends and the best."""
    import dataclasses

    import numpy as np
    import pandas as pd

    from oscillator.designing.chain_design import chain_design, worst_over

    chain = oscillator.load_system(ROOT / "docs" / "systems" / "blade-damper.toml")
    band = {"Omega": (0.6, 1.6)}
    design = chain_design(chain, {"platform.F": (0.05, 3.0)}, band, "x_max:blade")
    print(design.summary)
    grid = []
    for load in (0.02, 0.1, 0.2, 0.3, 0.6, 0.9, 1.5, 2.2, 3.0):
        found = worst_over(chain.with_values({"platform.F": load}), "x_max:blade", ("Omega", 0.6, 1.6))
        grid.append({"platform.F": load, "worst": found.value, "at": found.at})
    history = pd.concat([design.history, pd.DataFrame(grid)], ignore_index=True)
    shown = dataclasses.replace(design, history=history)
    values = np.linspace(0.6, 1.6, 101)
    sweeps = {
        load: oscillator.frequency_sweep(chain.with_values({"platform.F": load}), values)
        for load in (0.05, design.value, 3.0)
    }
    figure = shown.plot(sweeps)
    figure.savefig(ROOT / "docs" / "images" / "system-damper-design.png", dpi=80, bbox_inches="tight")


def main() -> None:
    if sys.argv[1:] == ["design"]:
        damper_design()
        return
    damper_design()
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
