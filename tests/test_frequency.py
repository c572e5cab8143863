"""The frequency response (issue 38): the branches over a span with their measures, and the slow
sweeps up and down with their jumps, against a hardening Duffing oscillator's folds.

The Duffing example runs end to end as docs/frequency.md shows it (about 24 s on one worker, the
default tier's longest setup): these tests are in the slow tier, which CI runs, until the
frequency response runs on the compiled path (issue 53)."""

import numpy as np
import pytest

from oscillator import InputError, frequency_response

pytestmark = pytest.mark.slow


def test_the_branch_folds_twice_and_is_measured_at_every_point(duffing):
    """One branch from 0.8 to 1.6 through both folds (the seeds on it are not continued again):
    stable up to the upper fold, unstable between the folds, stable after the lower."""
    assert len(duffing.branches) == 1 and duffing.branches[0].complete
    folds = sorted(duffing.folds.Omega)
    assert len(folds) == 2 and 1.09 < folds[0] < 1.10 < 1.19 < folds[1] < 1.2
    points = duffing.points
    assert len(points) == len(duffing.branches[0].points) and not points.x_pp_m1.isna().any()
    # at 1.15, between the folds, the branch passes three times: large and stable, then unstable,
    # then small and stable, in that order along it
    side = np.sign(points.Omega.to_numpy() - 1.15)
    crossings = np.flatnonzero(side[1:] != side[:-1])
    assert len(crossings) == 3
    assert points.stable.iloc[crossings].tolist() == [True, False, True]
    sizes = points.x_pp_m1.iloc[crossings].to_numpy()
    assert sizes[0] > sizes[1] > sizes[2] and sizes[0] > 3 * sizes[2]


def test_the_sweeps_jump_where_the_branch_folds(duffing):
    """Up, the large motion holds to the upper fold and drops at the first value past it; down, the
    small one holds to the lower fold and jumps up at the first value below it (to the sweep's
    resolution, 0.01)."""
    low, high = sorted(duffing.folds.Omega)
    (up,), (down,) = duffing.jumps("up"), duffing.jumps("down")
    assert high < up <= high + 0.01 + 1e-9 and low - 0.01 - 1e-9 <= down < low
    sweeps = duffing.sweeps
    before = sweeps[(sweeps.direction == "up") & (sweeps.Omega < up)].x_pp_m1.iloc[-1]
    after = sweeps[(sweeps.direction == "up") & (sweeps.Omega >= up)].x_pp_m1.iloc[0]
    assert before > 5 * after
    # every sweep value met a period-1 orbit, measured
    assert (sweeps.period == 1).all() and not sweeps.x_pp_m1.isna().any()


@pytest.mark.parametrize(
    ("arguments", "field"),
    [
        ({"param": "Q3"}, "param"),
        ({"span": (1.6, 1.3)}, "span"),
        ({"span": (1.3,)}, "span"),
        ({"span": (-1.0, 1.3)}, "Omega"),
        ({"period": 0}, "period"),
        ({"seeds": 1}, "seeds"),
    ],
)
def test_bad_input_is_refused_naming_the_field(arguments, field):
    with pytest.raises(InputError) as caught:
        frequency_response("instance-1", **({"param": "Omega", "span": (1.3, 1.85)} | arguments))
    assert caught.value.field == field


def test_the_figure_draws_the_branch_the_folds_and_the_jumps(duffing):
    """One panel per mass; stable solid and unstable dashed lines; the two folds marked on each
    panel; an arrow at each sweep's jump; a measure that is not one refused."""
    fig = duffing.plot("x_pp")
    top, bottom = fig.axes
    styles = {line.get_linestyle() for line in top.lines if line.get_color() not in ("0.35", "0.55")}
    assert {"-", "--"} <= styles  # the branch, stable and unstable
    keys = {
        text.get_text(): handle
        for handle, text in zip(fig.legends[0].legend_handles, fig.legends[0].texts, strict=True)
    }
    assert keys["stable orbits (each branch its colour)"].get_linestyle() == "-"
    assert keys["unstable orbits"].get_linestyle() == "--"
    assert keys["stable orbits (each branch its colour)"].get_color() == "0.2"  # not a branch's own colour
    folds = [line for line in top.lines if line.get_label() == "fold"]
    assert len(folds) == 2 and len([line for line in bottom.lines if line.get_label() == "fold"]) == 2
    assert len(top.texts) == 2  # the jump up and the jump down, as arrows
    assert top.get_ylabel() == "x_pp of m1 (m)" and bottom.get_xlabel() == "Omega (rad/s)"
    with pytest.raises(InputError) as caught:
        duffing.plot("x_ppp")
    assert caught.value.field == "measure"
