"""Draw the figures of docs/noise.md into docs/images/: the spectra of its first orbit
(``noise.png``), of its frequency response's stable points (``frequency-spectra.png``) and of the
rattler's orbit (``noise-rattler.png``), and the worked design's worst
impact power and right-stop strike over the band before and after (``noise-design-response.png``)
and the Pareto front between them (``noise-design-front.png``).

Usage: python scripts/noise_figures.py [spectra]   (``spectra``: the spectra alone)
"""

import sys
from pathlib import Path

import matplotlib as mpl

import oscillator as osc
from oscillator.io.cases import resolve_case
from oscillator.report.noise import spectra_response_figure

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"
#: docs/noise.md's problem: the clearance between the masses and the contact's damper.
PROBLEM = {
    "vary": {"d": (0.5, 2.2), "C3": (0.2, 2.0)},
    "over": {"Omega": (1.45, 1.6)},
    "band": 7,
    "starts": 2,
    "candidates": 8,
    "settings": osc.AttractorSettings(transient=100, record=8),
}


def spectra() -> None:
    """docs/noise.md's orbits' spectra: the article's system's, then its declared system's."""
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    orbit.noise().plot().savefig(IMAGES / "noise.png", dpi=110, bbox_inches="tight")
    print(f"wrote {IMAGES / 'noise.png'}")
    response = osc.frequency_response(resolve_case("instance-1", d=1, d1=3.5), "Omega", (1.45, 1.6), seeds=2)
    spectra_response_figure(response, response.noise_tables()[1]).savefig(IMAGES / "frequency-spectra.png", dpi=72)
    print(f"wrote {IMAGES / 'frequency-spectra.png'}")
    machine = osc.load_system(IMAGES.parent / "systems" / "rattler.toml")
    orbit = osc.find_orbit(machine, transient=100)
    orbit.noise().plot().savefig(IMAGES / "noise-rattler.png", dpi=110, bbox_inches="tight")
    print(f"wrote {IMAGES / 'noise-rattler.png'}")


def main() -> None:
    mpl.use("Agg")
    spectra()
    if sys.argv[1:] == ["spectra"]:
        return
    case = resolve_case("instance-1", d1=3.5)
    quieter = osc.design(case, objective="impact_power_left", constraints=["impact_max_right <= 4.6"], **PROBLEM)
    print(quieter.message, quieter.values, quieter.best.objective, quieter.runs)
    quieter.plot("response").savefig(IMAGES / "noise-design-response.png", dpi=110, bbox_inches="tight")
    traded = osc.design(case, objective=["impact_power_left", "impact_max_right"], front=5, **PROBLEM)
    print(traded.front.round(5).to_string())
    traded.plot("front").savefig(IMAGES / "noise-design-front.png", dpi=110, bbox_inches="tight")
    print(f"wrote {IMAGES / 'noise-design-response.png'} and {IMAGES / 'noise-design-front.png'}")


if __name__ == "__main__":
    main()
