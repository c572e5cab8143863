"""``oscillator frc`` and the frequency response's stages (issue 38): Instance 1's branches over
[1.3, 1.85] in one chain through the points where the corrector fails, the coexistence window at
Omega = 1.6 (Q2 = 71.165) with the sweeps' hysteresis, resume, and bad input."""

import re

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from conftest import DUFFING, FRC_WINDOW, rewritten
from oscillator import frequency_response, resolve_case, response, simulate
from oscillator.attractors.atlas import fresh_starts
from oscillator.attractors.responding import RESTART, orbit_state
from oscillator.cli.app import app
from test_orbits import BILINEAR


def discontinuities(found) -> list[float]:
    """Where the branches of ``found`` are not continuous: a located bifurcation whose sides lie
    apart (``jump`` above 1e-6, or NaN: a gap's end), and each end of a branch inside the span
    where the corrector failed or stalled."""
    rows = found.bifurcations
    points = list(rows.loc[~(rows.jump <= 1e-6), found.param])
    for branch in found.branches:
        if not branch.complete and ("corrector failed" in branch.message or "stalled" in branch.message):
            points.append(float(branch.points[found.param].iloc[-1]))
    return sorted(points)


@pytest.mark.slow
def test_instance_1_is_one_family_whose_sliding_points_the_sweeps_jump_across():
    """Over [1.3, 1.85] the period-1 orbit is one family of stable orbits, traced as branches that
    cover the span (restarts RESTART of it beyond each point where the corrector fails: no gap
    wider); no fold; the sweeps' orbits lie on the branches.  Where a rest interval appears or
    vanishes with a finite length (the orbit moves by 1e-3 at once: 1.3368, 1.365, 1.5994,
    1.6097) the orbit the sweep meets is not the continuation of the one before: each sweep jumps
    in every interval of its values holding such a point, and in no other."""
    found = frequency_response("instance-1", "Omega", (1.3, 1.85), workers=2)
    spans = sorted((b.points.Omega.min(), b.points.Omega.max()) for b in found.branches)
    assert spans[0][0] == 1.3 and max(high for _, high in spans) == 1.85
    reach = spans[0][1]
    for low, high in spans[1:]:
        assert low <= reach + RESTART * 0.55 + 1e-9, (low, reach)
        reach = max(reach, high)
    assert found.folds.empty and found.points.stable.all()
    breaks = discontinuities(found)
    assert len(breaks) >= 4
    for direction in ("up", "down"):
        rows = found.sweeps[found.sweeps.direction == direction]
        values, jumped = rows.Omega.to_numpy(), rows.jump.to_numpy(bool)
        for k in range(1, len(values)):
            low, high = sorted((values[k - 1], values[k]))
            assert jumped[k] == any(low < x < high for x in breaks), (direction, values[k], breaks)
    points = found.points.sort_values("Omega")
    for _, row in found.sweeps.iterrows():
        nearest = points.iloc[int(np.argmin(np.abs(points.Omega.to_numpy() - row.Omega)))]
        if abs(nearest.Omega - row.Omega) < 1e-12:  # a sweep value the branch passed: the same orbit
            assert row.x_pp_m2 == pytest.approx(nearest.x_pp_m2, abs=1e-7)
    inside = points[(points.Omega > 1.4) & (points.Omega < 1.55)]
    assert (inside.rest_m1 == 0).all() and (inside.rest_m2 == 0).all()
    assert (points[(points.Omega > 1.34) & (points.Omega < 1.36)].rest_m1 > 0).all()  # m1 sticks there


def brute_force_rests(case, values, periods: int = 400) -> list[float]:
    """m2's rest fraction over the last 10 of ``periods`` forcing periods at each value, each run
    from where the one before ended: a slow sweep by ``simulate`` alone."""
    from oscillator.hybrid.recording import SaveAt

    state, rests = case.initial.y, []
    for value in values:
        at = resolve_case(case, Omega=float(value), **dict(zip(("x1", "v1", "x2", "v2"), state, strict=True)))
        t_end = at.initial.t0 + periods * at.parameters.period
        run = simulate(at, t_end=t_end, save=SaveAt(steps=False, segments=True))
        last = t_end - 10 * at.parameters.period
        resting = sum(max(0.0, min(s.t1, t_end) - max(s.t0, last)) for s in run.segments if s.mode.sign(2) == 0)
        rests.append(resting / (t_end - last))
        state = tuple(float(v) for v in run.final_state[1:])
    return rests


@pytest.mark.slow
def test_a_family_that_sticks_beside_the_main_one_is_traced_and_its_jumps_placed_where_simulate_puts_them():
    """Instance 1 with Q1 = 4, Q2 = 2.2, d = d1 = 1.5, K6 = 2 over [1.6, 2.021] (issue 50): a stable
    family in which m2 sticks coexists with the main one over about [1.9686, 2.0198]; it was traced
    only over [2.0202, 2.021] (the restart after the sliding point went up only), so the sweep down
    rode a family on no branch, and neither sweep marked a jump.  Now the restart is continued both
    ways: a branch of sticking orbits spans [1.97, 2.02], the sweeps' orbits lie on branches, and
    each sweep jumps where a sweep by simulate alone leaves its family (rest_m2 appears going up at
    2.021, vanishes going down at 1.968375)."""
    case = resolve_case("instance-1", Q1=4, Q2=2.2, d=1.5, d1=1.5, K6=2)
    found = frequency_response(case, "Omega", (1.6, 2.021), seeds=3, sweep=17, workers=2)
    sticking = found.points[found.points.rest_m2 > 0.05]
    assert sticking.Omega.min() < 1.97 and sticking.Omega.max() == 2.021 and sticking.stable.all()
    for direction in ("up", "down"):
        rows = found.sweeps[found.sweeps.direction == direction].reset_index(drop=True)
        brute = np.array(brute_force_rests(case, rows.Omega.to_numpy()))
        np.testing.assert_allclose(rows.rest_m2, brute, atol=0.02)  # the same families, one by one
        left = np.flatnonzero((brute[1:] > 0.05) != (brute[:-1] > 0.05)) + 1
        assert rows.Omega[rows.jump].tolist() == rows.Omega[left].tolist(), direction
    assert found.jumps("up") == [2.021] and found.jumps("down") == [pytest.approx(1.968375)]
    from oscillator.attractors.responding import on_branch

    for _, row in found.sweeps.iterrows():  # every orbit the sweeps met lies on a branch
        state = row[["x1", "v1", "x2", "v2"]].to_numpy(float)
        assert any(on_branch(case, branch, row.Omega, state) for branch in found.branches), row.Omega


@pytest.mark.slow
def test_an_impacting_systems_impact_speeds_are_those_of_its_orbits_events():
    """Instance 1's system with d = 1, d1 = 3.5 (docs/frequency.md), over [1.65, 1.8] around its
    grazing: contacts with the right stop and between the masses at every branch point; at a few
    points the largest approach speeds equal those read from the events of ``simulate`` run one
    period from the branch's orbit; the energy closes at every point."""
    from oscillator import simulate
    from oscillator.orbits.response import impact_speeds

    case = resolve_case("instance-1", d=1.0, d1=3.5)
    found = frequency_response(case, "Omega", (1.65, 1.8), seeds=2, sweep=5, workers=2)
    points = found.points
    assert (points.onsets_right == 1).all() and points.onsets_left.isin([1.0, 2.0]).all()
    assert ((points.onsets_left == 2) == (points.Omega < 1.7306)).mean() > 0.99  # a grazing ends one
    balance = points.energy_forcing + points.energy_feedback
    balance -= points.energy_dampers + points.energy_contact + points.energy_friction
    assert np.max(np.abs(balance)) < 1e-6 * points.energy_friction.max()
    for _, row in points.iloc[:: max(len(points) // 6, 1)].iterrows():
        branch = found.branches[int(row.branch)]
        start = dict(zip(("x1", "v1", "x2", "v2"), (float(row[n]) for n in ("x1", "v1", "x2", "v2")), strict=True))
        at = resolve_case(case, Omega=float(row.Omega), t0=branch.section, **start)
        events = simulate(at, t_end=at.initial.t0 + at.parameters.period, rtol=1e-12, atol=1e-12).events
        for stop in ("right", "left"):
            assert row[f"impact_max_{stop}"] == pytest.approx(impact_speeds(events, stop).max(), abs=1e-6)


# 9 s, the default tier's longest call: in the slow tier, which CI runs, until the frequency
# response runs on the compiled path (issue 53).
@pytest.mark.slow
def test_a_period_doubling_gives_the_period_2_branch_that_the_sweep_meets():
    """docs/frequency.md's example: the period-1 branch doubles at 2.4253769 and is unstable
    beyond; the period-2 branch born there starts within 1e-3 of the span beyond it, is stable,
    and is the orbit the sweep up
    lands on (x_pp of m1 to 1e-3 from the branch's points, to 1e-7 from its orbit refined at 2.5);
    the sweeps cross the doubling without a jump."""
    from pathlib import Path

    import oscillator as osc

    page = (Path(__file__).resolve().parents[1] / "docs" / "frequency.md").read_text(encoding="utf-8")
    block = page.split("**A period doubling.**", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    scope = {"osc": osc}
    exec(compile(block, "docs/frequency.md", "exec"), scope)  # the page's example, as shown
    assert scope["BILINEAR"] == BILINEAR
    case, found = resolve_case("instance-1", **BILINEAR), scope["found"]
    single, double = found.branches
    (row,) = single.bifurcations.itertuples()
    assert row.kind == "period_doubling" and abs(row.Omega - 2.4253769) < 1e-6
    assert double.period == 2 and 0 < double.points.Omega.min() - row.Omega <= 1e-3 * 0.7 + 1e-9
    assert double.points.stable.all() and not single.points[single.points.Omega > row.Omega + 1e-3].stable.any()
    points = found.points[found.points.period == 2].sort_values("Omega")
    up = found.sweeps[(found.sweeps.direction == "up") & (found.sweeps.Omega > points.Omega.min())]
    assert (up.period == 2).all()
    np.testing.assert_allclose(up.x_pp_m1, np.interp(up.Omega, points.Omega, points.x_pp_m1), atol=1e-3)
    # at 2.5, Newton from the branch's state there reaches the orbit the sweep measured
    guess = [np.interp(2.5, points.Omega, points[name]) for name in ("x1", "v1", "x2", "v2")]
    at = resolve_case(case, Omega=2.5)
    state = orbit_state(at, 2, np.array(guess))
    begin = dict(zip(("x1", "v1", "x2", "v2"), (float(v) for v in state), strict=True))
    exact = response(resolve_case(at, **begin), 2).columns()["x_pp_m1"]
    assert up[np.isclose(up.Omega, 2.5)].x_pp_m1.iloc[0] == pytest.approx(exact, abs=1e-7)
    # the doubling is supercritical: the sweep's orbit goes over to the period-2 one continuously
    # (both are fixed points of the period-2 map, and meet at the doubling): no jump
    assert found.jumps("up") == [] and found.jumps("down") == []


#: The window's frequency response (16 fresh starts, 41 sweep values) takes about 19 s on one worker,
#: the default tier's longest setup: its tests are in the slow tier, which CI runs, until the
#: frequency response runs on the compiled path (issue 53).
WINDOW_TIER = pytest.mark.slow


@pytest.fixture(scope="module")
def window(once):
    case = resolve_case("instance-1", Q2=71.165)
    return once(
        "window", lambda: frequency_response(case, "Omega", (1.5999, 1.6001), states=fresh_starts(case, 16), sweep=41)
    )


@WINDOW_TIER
def test_the_coexistence_at_omega_1_6_is_a_hysteresis_window(window):
    """At Q2 = 71.165 the orbit without rest and the one in which m2 rests coexist on a window
    around 1.6 (docs/attractors.md): the first branch gains its rest with a jump at its sliding
    onset, the second (seeded at 1.6) runs onto the first there and ends below; the sweep up
    jumps at the first value past the onset, the sweep down at the first value below the second
    branch's end."""
    onset = window.bifurcations[window.bifurcations.kind == "sliding_onset"].Omega
    assert len(onset) == 1
    onset = float(onset.iloc[0])
    seeded = window.branches[1:]  # the orbit with rest, from the seed at 1.6, up and down
    assert len(seeded) == 2 and all(b.points.Omega.max() <= onset for b in seeded)
    low = min(float(b.points.Omega.min()) for b in seeded)
    assert 1.59997 < low < 1.6 < onset < 1.60004
    step = 0.0002 / 40
    (up,), (down,) = window.jumps("up"), window.jumps("down")
    assert onset < up <= onset + step + 1e-12 and low - step - 1e-12 <= down < low
    points = window.points
    first, second = (points[points.branch == k] for k in (0, 2))
    at = [part.iloc[int(np.argmin(np.abs(part.Omega.to_numpy() - 1.6)))] for part in (first, second)]
    assert all(abs(row.Omega - 1.6) < 1e-5 for row in at)
    assert at[0].rest_m2 == 0 and at[1].rest_m2 > 1e-3  # both at 1.6: one rests, one does not


def test_an_interrupted_frequency_response_keeps_its_parts_and_resumes_to_the_same_tables(tmp_path, small_frc):
    """Ctrl-C in the measures stage: the seeds' branches and the measures finished are kept;
    run again into the store, it goes on from there (its progress counts the kept points at once)
    to the tables of an uninterrupted run (the command's: ``small_frc``)."""
    import oscillator as osc
    from oscillator.attractors.frequency import frequency_store

    case = resolve_case("instance-1", Q2=71.165)
    arguments = ("Omega", (1.5999, 1.6001))
    options = {"states": fresh_starts(case, 16), "seeds": 2, "sweep": 3}
    whole = osc.read_run(small_frc)
    first = len(whole.branches[0].points)

    def stop_in_the_measures(done, total):
        if done > 2 + 2 * 3 + first:  # the 2 seeds, the sweeps, the first branch's points and a chunk more
            raise KeyboardInterrupt

    store = frequency_store(tmp_path / "frc", case, *arguments, **options)
    store.check()
    store.open()
    with pytest.raises(KeyboardInterrupt):
        frequency_response(case, *arguments, store=store, progress=stop_in_the_measures, **options)
    kept = sorted(p.name for p in store.parts.iterdir())
    assert {f"seed-{k:04d}.parquet" for k in range(2)} | {"sweep-up.parquet", "sweep-down.parquet"} <= set(kept)
    assert "from-sweeps.parquet" in kept and "measures-0000.parquet" in kept
    assert not all(f"measures-{b:04d}.parquet" in kept for b in range(len(whole.branches)))
    again = frequency_store(tmp_path / "frc", case, *arguments, **options)
    again.check()
    seen = []
    found = frequency_response(case, *arguments, store=again, progress=lambda d, t: seen.append(d), **options)
    assert first in np.diff(seen) and again.reused == len(kept)  # the kept branch's points counted at once
    pd.testing.assert_frame_equal(found.points, whole.points, check_exact=True)
    pd.testing.assert_frame_equal(found.sweeps, whole.sweeps, check_exact=True, check_dtype=False)


@pytest.mark.slow
def test_the_frequency_response_is_the_same_on_dask():
    """A frequency response of the window (4 starts at each of 2 seeds, 5 sweep values) on a Dask
    cluster: the same tables as in one process."""
    distributed = pytest.importorskip("distributed")
    case = resolve_case("instance-1", Q2=71.165)
    options = {"states": fresh_starts(case, 4), "seeds": 2, "sweep": 5}
    here = frequency_response(case, "Omega", (1.5999, 1.6001), **options)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as client:
            dask = frequency_response(case, "Omega", (1.5999, 1.6001), client=client, **options)
    assert len(here.points) > 10 and here.jumps("up") == [pytest.approx(1.60005)]  # the first value past 1.60003
    pd.testing.assert_frame_equal(dask.points, here.points)
    pd.testing.assert_frame_equal(dask.sweeps, here.sweeps)


@WINDOW_TIER
def test_a_jump_is_a_change_of_attractor_not_of_signature(window):
    """Between two values of the window's sweep up the orbit met is either the continuation of the
    one before (its family, through the grazing's kink too) or not: at the sliding onset the rest
    appears with a finite length (the orbit moves by 3e-3 at once) and the family of the orbit
    before ends; jumps() recomputed from the sweep's orbits gives the table's column."""
    from oscillator.attractors.responding import follows, jumps

    case = resolve_case("instance-1", Q2=71.165)
    up = window.sweeps[window.sweeps.direction == "up"].reset_index(drop=True)
    states = up[["x1", "v1", "x2", "v2"]].to_numpy(float)
    onset = int(np.flatnonzero(up.jump)[0])
    assert up.rest_m2.iloc[onset - 1] == 0 and up.rest_m2.iloc[onset] > 1e-3  # the rest appears there
    pairs = {onset - 2: True, onset - 1: False, onset: True}  # before, across and after the onset
    for k, continuous in pairs.items():
        a, b = (up.Omega.iloc[k], states[k]), (up.Omega.iloc[k + 1], states[k + 1])
        assert follows(case, "Omega", a, b, 1) is continuous, k
    met = [(float(v), int(p), s) for v, p, s in zip(up.Omega, up.period, states, strict=True)]
    assert jumps(case, "Omega", met).tolist() == up.jump.tolist()


def test_a_landing_that_has_not_settled_is_told_apart_from_an_aperiodic_one():
    """Beside the Duffing oscillator's upper fold the large orbit's multiplier is near 1: 30
    periods do not settle it (period 0, where the sweep called the next value a jump); Newton
    from its last point finds the stable orbit it converges to, the one a long run reaches."""
    from oscillator.attractors.mapping import AttractorSettings, land
    from oscillator.attractors.responding import settled_orbit

    case = resolve_case("instance-1", **{**DUFFING, "Omega": 1.19})
    settings = AttractorSettings(transient=30, record=8, settle=False)
    landing = land(case, settings, 0, (1.5, 0.0, 0.0, 0.1))
    assert landing.ok and landing.period == 0
    period, state = settled_orbit(case, landing, settings)
    start = resolve_case(case, x1=1.5, v1=0.0, x2=0.0, v2=0.1)
    long = simulate(start, t_end=case.initial.t0 + 3000 * case.parameters.period)
    assert period == 1 and np.allclose(state, long.final_state[1:], atol=1e-6)


ARGS = FRC_WINDOW


def test_the_command_resumes_from_its_parts_to_the_same_tables(tmp_path, small_frc):
    """The command (its folder computed once: ``small_frc``) run again reads every part back; with
    a part deleted, it computes that part again, to the same tables, saying how far it is."""
    import shutil

    import oscillator.cli.resumable as resumable

    runner = CliRunner()
    folder = tmp_path / "frc"
    shutil.copytree(small_frc, folder)
    command = [*ARGS, "--seeds", "2", "--sweep", "3", "--workers", "1", "--out", str(folder), "--no-plots"]
    points = pd.read_parquet(folder / "points.parquet")
    parts = sorted(p.name for p in (folder / "parts").iterdir())
    again = runner.invoke(app, command)
    assert f"resumed: {len(parts)} parts read" in again.stdout and "sweep up: jumps at 1.6001" in again.stdout
    (folder / "parts" / "measures-0001.parquet").unlink()
    (folder / "parts" / "sweep-down.parquet").unlink()
    every, resumable.PROGRESS_EVERY = resumable.PROGRESS_EVERY, 0.0  # a line at each task (not a terminal)
    try:
        third = runner.invoke(app, command)
    finally:
        resumable.PROGRESS_EVERY = every
    assert f"resumed: {len(parts) - 2} parts read" in third.stdout
    lines = [line for line in third.stderr.splitlines() if ": frequency response over Omega:" in line]
    assert len(lines) > 2 and re.search(r": \d+ of \d+ tasks, \d+ s(, about \d+ s left)?$", lines[-1]), lines[-3:]
    pd.testing.assert_frame_equal(pd.read_parquet(folder / "points.parquet"), points, check_exact=True)
    assert pd.read_parquet(folder / "sweeps.parquet").jump.sum() == 2


def _strings(frame):
    return frame.assign(x1=frame["x1"].astype(str))


DAMAGES = {
    # (the part damaged, how, what the refusal says)
    "bytes": ("seed-0000", lambda p: p.write_bytes(b"not parquet"), "it cannot be read"),
    "metadata": ("seed-0000", lambda p: rewritten(p, lambda f: f, [{"section": 0.0}]), "not a branch's"),
    "a row dropped": ("measures-0000", lambda p: rewritten(p, lambda f: f.iloc[:-1]), "rows, where its task has"),
    "sweep rows twice": ("sweep-up", lambda p: rewritten(p, lambda f: pd.concat([f, f])), "rows, where its task has"),
    "Omega x1000 in a sweep": (
        "sweep-up",
        lambda p: rewritten(p, lambda f: f.assign(Omega=1000 * f.Omega)),
        "its column 'Omega' is not its task's values",
    ),
    "Omega x1000 in a seed": (
        "seed-0000",
        lambda p: rewritten(p, lambda f: f.assign(Omega=1000 * f.Omega)),
        "lies outside the span",
    ),
    "up replaced by down": ("sweep-up", lambda p: p.write_bytes(p.with_name("sweep-down.parquet").read_bytes()),
                            "it holds another task's result"),
    "a seed swapped": ("seed-0000", lambda p: p.write_bytes(p.with_name("seed-0001.parquet").read_bytes()),
                       "it holds another task's result"),
    "strings in a column": ("seed-0000", lambda p: rewritten(p, _strings), "its column 'x1' is not numbers"),
}  # fmt: skip


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_or_foreign_part_is_refused_by_name(tmp_path, small_frc, damage):
    """A part that cannot be read, holds another task's result (the up sweep replaced by the down,
    a seed's part by another's: they were merged), the wrong rows (a sweep's rows twice: 15
    instead of 10), values outside the span (Omega x1000) or strings where numbers belong (a
    traceback): each refused in one line naming the part, exit 2, before anything is computed."""
    import shutil

    folder = tmp_path / "frc"
    shutil.copytree(small_frc, folder)
    command = [*ARGS, "--seeds", "2", "--sweep", "3", "--out", str(folder), "--no-plots"]
    name, damage_it, said = DAMAGES[damage]
    damage_it(folder / "parts" / f"{name}.parquet")
    done = CliRunner().invoke(app, command)
    assert done.exit_code == 2 and f"{name}.parquet is damaged (" in done.stderr and said in done.stderr, done.stderr
    assert len(done.stderr.splitlines()) == 1


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--param", "Omega", "1.85", "1.3"], "--param must be two finite numbers, low < high"),
        (["--param", "Omeg", "1.3", "1.5"], "--param 'Omeg' is not a parameter"),
        (["--param", "Omega", "1.3", "1.5", "--period", "0"], "--period must be a whole number from 1"),
        (["--param", "Omega", "1.3", "1.5", "--measure", "loudness"], "--measure must be one of x_max"),
        (["--param", "Omega", "1.3", "1.5", "--starts", "0"], "--starts must be a whole number"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, extra, said):
    folder = tmp_path / "frc"
    done = CliRunner().invoke(app, ["frc", "instance-1", *extra, "--out", str(folder)])
    assert done.exit_code == 2 and done.stderr.startswith(f"error: {said}") and len(done.stderr.splitlines()) == 1
    assert not folder.exists()


@pytest.mark.parametrize("extra", [["--set", "max_num_steps=5"]])
def test_a_span_without_a_periodic_orbit_writes_empty_tables_and_says_so(tmp_path, extra):
    """Where no periodic orbit is found (every landing failing), the command
    writes the tables with their columns and no row, a report that says so, and exits 1 (it gave a
    traceback, and every resume repeated it); run again, it resumes to the same."""
    folder = tmp_path / "frc"
    command = ["frc", "instance-1", "--param", "Omega", "1.5", "1.6", "--seeds", "2", "--sweep", "3"]
    command += [*extra, "--workers", "1", "--out", str(folder)]
    for attempt in range(2):
        done = CliRunner().invoke(app, command)
        assert done.exit_code == 1, done.output
        assert done.stderr.startswith("error: no periodic orbit of period 1 was found over Omega's span")
        assert len(done.stderr.splitlines()) == 1 and "Traceback" not in done.output
        points = pd.read_parquet(folder / "points.parquet")
        assert len(points) == 0 and {"Omega", "x1", "mu1_re", "stable", "x_pp_m1", "impact_max_left"} <= set(points)
        sweeps = pd.read_parquet(folder / "sweeps.parquet")
        assert len(sweeps) == 6 and "x_pp_m1" in sweeps
        assert "No periodic orbit of period 1 was found" in (folder / "report.md").read_text(encoding="utf-8")
        assert (folder / "figures" / "frequency-x-pp.png").exists()
        assert ("resumed:" in done.stdout) == (attempt == 1)


STICKING = {"Q1": 4, "Q2": 2.2, "d": 1.5, "d1": 1.5, "K6": 2}


def test_a_branch_that_stalls_where_a_contact_begins_ends_there():
    """The orbit at Omega = 2.06 in which m2 rests all period, continued down: where m1 begins to
    touch m2's stop (2.023714) the corrector's steps went back and forth without advancing, 1234 of
    1315 points at one value (250 s); the stall is seen within a window of steps and the branch ends
    there, saying so, with its points before the stall."""
    from oscillator import continue_orbit
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.attractors.responding import seed_orbits
    from oscillator.errors import Reason
    from oscillator.orbits.continuation import STALL_WINDOW

    case = resolve_case("instance-1", **STICKING)
    (resting,) = [s for s in seed_orbits(case, "Omega", 2.06, 1, None, AttractorSettings()) if s[3] == 0.0]
    branch = continue_orbit(case, param="Omega", start=2.06, stop=2.022, guess=resting, max_points=3000)
    assert not branch.complete and branch.reason == Reason.NO_CONVERGENCE and "stalled" in branch.message
    values = branch.points.Omega.to_numpy()
    assert len(values) < 10 * STALL_WINDOW and values[-1] == pytest.approx(2.0237143, abs=1e-6)
    assert np.count_nonzero(np.abs(values - values[-1]) < 1e-7) <= 3  # the back and forth undone


@pytest.mark.slow
def test_the_frequency_response_goes_on_beyond_a_stalled_branch():
    """Over (2.022, 2.06) the frequency response took 250 s (one branch at max_points): now every
    branch ends at the span, a failure or a stall in a bounded number of points, and the orbit
    on the far side of the stall (the family turns back there) is traced too."""
    case = resolve_case("instance-1", **STICKING)
    found = frequency_response(case, "Omega", (2.022, 2.06), seeds=3, sweep=5, workers=2)
    from oscillator.errors import Reason

    assert all(branch.reason != Reason.MAX_POINTS and len(branch.points) < 500 for branch in found.branches)
    stalled = [b for b in found.branches if "stalled" in b.message]
    assert stalled
    end = float(stalled[0].points.Omega.iloc[-1])
    starts = [float(b.points.Omega.iloc[0]) for b in found.branches]
    assert any(abs(start - end) == pytest.approx(RESTART * 0.038, abs=1e-9) for start in starts)


def _same_response(back, found):
    """Two frequency responses hold the same tables and branches, to the bit."""
    pd.testing.assert_frame_equal(back.points, found.points, check_exact=True)
    for name in ("sweeps", "bifurcations"):  # text columns read back as pandas' strings
        pd.testing.assert_frame_equal(getattr(back, name), getattr(found, name), check_exact=True, check_dtype=False)
    assert (back.param, back.period, len(back.branches)) == (found.param, found.period, len(found.branches))
    for a, b in zip(back.branches, found.branches, strict=True):
        pd.testing.assert_frame_equal(a.points, b.points, check_exact=True)
        pd.testing.assert_frame_equal(a.bifurcations, b.bifurcations, check_exact=True, check_dtype=False)
        assert (a.section, a.period, a.complete, a.message, a.reason) == (
            b.section,
            b.period,
            b.complete,
            b.message,
            b.reason,
        )


@WINDOW_TIER
def test_a_frequency_response_saves_reads_back_and_rebuilds_its_report(tmp_path, window, small_frc, monkeypatch):
    """``save`` writes the command's folder and ``read_run`` gives back the same response (the
    branches with their endings and bifurcations, the points, the sweeps), computing nothing; a
    command's finished folder reads back too, and ``oscillator report`` writes its tables, figures
    and report again; one without ``response.json`` (unfinished) or with it damaged is refused
    naming it; in Jupyter the case's name is text."""
    import dataclasses
    import json
    import shutil

    import oscillator as osc
    import oscillator.attractors.frequency as computing

    monkeypatch.setattr(computing, "frequency_response", None)  # reading computes nothing
    back = osc.read_run(window.save(tmp_path / "saved"))
    _same_response(back, window)
    assert back.jumps("up") == window.jumps("up") == [pytest.approx(1.60003, abs=1e-5)]
    folder = tmp_path / "frc"
    shutil.copytree(small_frc, folder)
    command = osc.read_run(folder)
    assert isinstance(command, osc.FrequencyResponse) and command.case.name == "instance-1"
    pd.testing.assert_frame_equal(osc.read_run(command.save(tmp_path / "again")).points, command.points)
    (folder / "report.md").unlink()
    done = CliRunner().invoke(app, ["report", str(folder)])
    assert done.exit_code == 0 and "report rebuilt (the frequency response)" in done.output, done.output
    assert (folder / "report.md").is_file() and (folder / "figures" / "frequency-x-pp.png").is_file()
    _same_response(osc.read_run(folder), command)
    kept = json.loads((folder / "response.json").read_text())
    kept["branches"][0]["section"] = "soon"
    (folder / "response.json").write_text(json.dumps(kept))
    with pytest.raises(osc.InputError, match=r"response.json disagree \(a branch's section or period is not a number"):
        osc.read_run(folder)
    (folder / "response.json").unlink()
    done = CliRunner().invoke(app, ["report", str(folder)])
    assert done.exit_code == 2 and "not a finished frequency response: response.json is missing" in done.stderr
    assert "same --out" in done.stderr and len(done.stderr.splitlines()) == 1
    shown = dataclasses.replace(window, case=dataclasses.replace(window.case, name="<script>"))
    assert "<script>" not in shown._repr_html_() and "&lt;script&gt;" in shown._repr_html_()


@WINDOW_TIER
def test_a_response_without_bifurcations_writes_a_table_the_explorer_reads(tmp_path, window):
    """No branch with a bifurcation: ``bifurcations.parquet`` had untyped empty columns, which the
    explorer refused as damaged ("its column 'branch' is not numbers"); now each is of its kind."""
    import dataclasses

    from oscillator.attractors.frequency import frequency_store
    from oscillator.exploring.maps import picture_of
    from oscillator.report.frequency import write_frequency

    plain = tuple(dataclasses.replace(b, bifurcations=b.bifurcations.iloc[:0]) for b in window.branches)
    found = dataclasses.replace(window, branches=plain)
    rows = found.bifurcations
    assert rows.empty and rows["branch"].dtype.kind == "i" and rows["Omega"].dtype.kind == "f"
    folder = tmp_path / "frc"
    frequency_store(folder, found.case, "Omega", (1.5999, 1.6001)).open()
    write_frequency(found, folder, plots=False)
    picture = picture_of(folder)
    assert picture.kind == "frc" and picture.marks.empty and len(picture.points) == 2 * len(found.points)
