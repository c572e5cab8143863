"""Draw the figures shown in docs/cli.md (one of each kind) into docs/images/.

Usage: python scripts/docs_figures.py
"""

import shutil
import tempfile
from pathlib import Path

from oscillator import simulate
from oscillator.report.figures import write_figures

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"
SHOWN = {  # panel -> the instance that shows it best
    "fig-a-displacement": "instance-3",  # left contact
    "fig-b-velocity": "instance-1",  # rest intervals
    "fig-c-phase": "instance-2",  # grazing
    "fig-d-forces": "instance-1",  # flow barriers
}


def main() -> None:
    IMAGES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        for panel, name in SHOWN.items():
            result = simulate(name)
            case = result.case
            folder = Path(scratch) / name
            if not folder.exists():
                write_figures(result.trajectory, result.events, case.parameters, (case.initial.t0, *case.initial.y),
                              folder, title=name)  # fmt: skip
            shutil.copy(folder / f"{panel}.png", IMAGES / f"{name}-{panel}.png")
            print(f"wrote {IMAGES / f'{name}-{panel}.png'}")


if __name__ == "__main__":
    main()
