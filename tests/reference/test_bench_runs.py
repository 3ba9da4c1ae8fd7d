"""`rtlab bench --runs N` and `rtlab bench --summarize FILE...`: several runs as medians, with
the range of rtlab's ratio over the runs, each ratio taken within one run (as the README's
tables are made)."""

from __future__ import annotations

import json
from functools import partial

import pytest

from reference.bench import (
    SUITES,
    RunsError,
    format_summary,
    format_summary_markdown,
    read_runs,
    speed_words,
    suite_classic,
    summarize_runs,
    summarize_scaling,
)
from tracer.cli import main

MACHINE = {"machine": "m", "cpu_model": "cpu", "cpu_count": 2, "compiler": "cc"}


def row(renderer, value, threads=1, unit="s", case="ex25", **extra):
    metric = {"s": "seconds", "Mrays/s": "mrays_per_s"}.get(unit, unit)
    return {"suite": "classic", "case": case, "renderer": renderer, "threads": threads,
            "metric": metric, "value": value, "unit": unit, **MACHINE, **extra}  # fmt: skip


# Three runs in which the machine drifts: rtlab's ratio to POV-Ray is 10, 12 and 8 within the
# runs (median 10, range 8-12), while the medians of the times (rtlab 2.0 s, POV-Ray 16 s)
# would give 8: a summary that divided medians would be wrong here.
DRIFTING = [
    [row("rtlab", 1.0), row("povray", 10.0)],
    [row("rtlab", 3.0), row("povray", 36.0)],
    [row("rtlab", 2.0), row("povray", 16.0)],
]


def by(rows, renderer, threads=1):
    return next(r for r in rows if r["renderer"] == renderer and r["threads"] == threads)


def test_each_ratio_is_taken_within_its_run():
    rows = summarize_runs(DRIFTING)
    povray = by(rows, "povray")
    assert povray["ratios"] == [10.0, 12.0, 8.0]
    assert (povray["ratio"], povray["ratio_min"], povray["ratio_max"]) == (10.0, 8.0, 12.0)
    assert povray["value"] == 16.0 and povray["values"] == [10.0, 36.0, 16.0]
    assert povray["runs"] == 3 and povray["cpu_model"] == "cpu"
    ours = by(rows, "rtlab")
    assert ours["value"] == 2.0 and "ratio" not in ours  # rtlab has no ratio to itself


def test_a_throughput_ratio_is_ours_over_theirs_and_a_time_theirs_over_ours():
    runs = [[row("rtlab", 30.0, unit="Mrays/s"), row("embree", 20.0, unit="Mrays/s")],
            [row("rtlab", 33.0, unit="Mrays/s"), row("embree", 22.0, unit="Mrays/s")]]  # fmt: skip
    embree = by(summarize_runs(runs), "embree")
    assert embree["ratios"] == [1.5, 1.5] and embree["ratio"] == 1.5


def test_the_gain_from_the_second_thread_is_summarised_run_by_run():
    runs = [
        [row("rtlab", 0.10), row("rtlab", 0.05, threads=2), row("povray", 1.0)],
        [row("rtlab", 0.12), row("rtlab", 0.05, threads=2), row("povray", 1.1)],
        [row("rtlab", 0.10), row("rtlab", 0.052, threads=2), row("povray", 0.9)],
    ]
    gains = summarize_scaling(runs)
    assert gains[("classic", "ex25", "rtlab")] == pytest.approx([2.0, 2.4, 0.10 / 0.052])
    assert ("classic", "ex25", "povray") not in gains  # POV-Ray ran on one thread only
    text = format_summary(runs)
    assert "classic: ex25, 1 -> 2 threads: rtlab 2.00x [1.92-2.40]" in text
    assert text.splitlines()[0] == "3 runs: medians, and rtlab's ratio's range over the runs"


def test_the_markdown_table_is_the_readmes():
    table = format_summary_markdown(DRIFTING, "rtlab bench classic --runs 3").splitlines()
    assert table[0] == "| case | threads | rtlab | povray |"
    assert table[2] == "| ex25 | 1 | 2 s | 16 s (rtlab 10.00x [8.00-12.00]) |"
    assert table[-1].startswith("3 runs: medians, and rtlab's ratio's range over the runs.")
    assert "Core built by cc. Command: `rtlab bench classic --runs 3`." in table[-1]


def test_times_to_error_are_made_in_each_run_then_summarised():
    # As tests/reference/test_compare_cli.py's single run: RMSE = c / sqrt(seconds), the other
    # renderer's c twice rtlab's, so it needs 4x rtlab's time to any error, in every run.
    def run(scale):
        return [{"suite": "convergence", "case": "box", "renderer": name, "threads": 2,
                 "metric": "rmse", "unit": "", "value": c / t**0.5, "seconds": t * scale,
                 **MACHINE}
                for name, c in (("rtlab", 1.0), ("other", 2.0)) for t in (1.0, 4.0)]  # fmt: skip

    rows = summarize_runs([run(1.0), run(1.5)])
    other = by(rows, "other", threads=2)
    assert other["case"] == "box, time to RMSE 0.75"
    assert other["ratios"] == pytest.approx([4.0, 4.0]) and other["runs"] == 2


def test_one_run_summarised_is_its_figures_without_ranges():
    text = format_summary(DRIFTING[:1])
    assert text.splitlines()[0] == "1 run"
    assert "  povray             10.0000 s   rtlab is 10.00x faster\n" in text + "\n"
    table = format_summary_markdown(DRIFTING[:1], "c")
    assert "| ex25 | 1 | 1 s | 10 s (rtlab 10.00x) |" in table and "1 run. CPU" in table


def test_read_runs_splits_a_file_of_several_runs_and_refuses_mixed_machines(tmp_path):
    several = tmp_path / "several.json"
    rows = [{**r, "run": n} for n, run in enumerate(DRIFTING, 1) for r in run]
    several.write_text(json.dumps(rows))
    one = tmp_path / "one.json"
    one.write_text(json.dumps(DRIFTING[0]))
    assert [len(r) for r in read_runs([several, one])] == [2, 2, 2, 2]
    other = tmp_path / "xeon.json"
    other.write_text(json.dumps([{**r, "cpu_model": "Intel Xeon"} for r in DRIFTING[0]]))
    with pytest.raises(RunsError, match=r"xeon\.json: a run on Intel Xeon .* do not mix"):
        read_runs([one, other])
    rebuilt = tmp_path / "gcc.json"
    rebuilt.write_text(json.dumps([{**r, "compiler": "GCC 12"} for r in DRIFTING[0]]))
    with pytest.raises(RunsError, match=r"gcc\.json: .*core built by GCC 12"):
        read_runs([one, rebuilt])


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("{not json", r"bad\.json: not JSON"),
        ('{"case": "ex25"}', r"bad\.json: expected the list of rows `rtlab bench --json` writes"),
        ('[{"case": "ex25", "value": 1}]', r"each with case, metric, renderer, threads"),
        ("[]", r"bad\.json: expected the list of rows"),
    ],
)
def test_read_runs_names_the_file_that_is_not_bench_rows(tmp_path, text, expected):
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    with pytest.raises(RunsError, match=expected):
        read_runs([bad])
    with pytest.raises(RunsError, match=r"missing\.json: cannot read it"):
        read_runs([tmp_path / "missing.json"])


def test_summarize_through_the_cli(tmp_path, capsys):
    paths = []
    for n, run in enumerate(DRIFTING, 1):
        paths.append(tmp_path / f"classic-{n}.json")
        paths[-1].write_text(json.dumps(run))
    md = tmp_path / "table.md"
    args = ["bench", "--summarize", *map(str, paths), "--markdown", str(md)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "  povray             16.0000 s   rtlab is 10.00x faster [8.00-12.00]" in printed
    table = md.read_text()
    assert "| ex25 | 1 | 2 s | 16 s (rtlab 10.00x [8.00-12.00]) |" in table
    assert f"Command: `rtlab bench --summarize {' '.join(map(str, paths))}`." in table
    assert sorted(p.name for p in tmp_path.iterdir()) == [*(p.name for p in paths), "table.md"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["bench"], "bench: which suite? expected all or classic"),
        (["bench", "classic", "--summarize", "a.json"], "give no suite, no --runs"),
        (["bench", "--summarize", "a.json", "--json", "b.json"], "writes no rows (--json)"),
        (["bench", "--summarize", "nowhere.json"], "nowhere.json: cannot read it"),
    ],
)
def test_bench_usage_errors_say_what_was_expected(capsys, args, message):
    assert main(args) == 2
    assert message in capsys.readouterr().err


def test_runs_through_the_cli(tmp_path, capsys, monkeypatch):
    """`rtlab bench classic --runs 2`, the suite made small (one repeat, one thread, 64x32):
    one JSON file of both runs' rows, each with its run's number, and a table of medians with
    the range of each ratio; read back, the file gives the same summary."""
    small = partial(suite_classic, repeats=1, threads=(1,), width=64, height=32)
    monkeypatch.setitem(SUITES, "classic", small)
    js, md = tmp_path / "out" / "runs.json", tmp_path / "out" / "runs.md"
    assert main(["bench", "classic", "--runs", "2", "--json", str(js), "--markdown", str(md)]) == 0
    printed = capsys.readouterr().out
    assert "run 1 of 2" in printed and "run 2 of 2" in printed
    assert f"rows of the 2 runs in {js}" in printed
    rows = json.loads(js.read_text())
    assert sorted((r["run"], r["renderer"]) for r in rows) == [
        (n, name) for n in (1, 2) for name in ("mitsuba-llvm", "povray", "rtlab")
    ]
    table = md.read_text().splitlines()
    assert table[2].startswith("| ex25-64x32 | 1 | ") and table[2].count("x [") == 2, table[2]
    assert table[-1].endswith(f"Command: `rtlab bench classic --runs 2 --json {js}`.")
    assert format_summary(read_runs([js])) in printed
    assert sorted(p.name for p in js.parent.iterdir()) == ["runs.json", "runs.md"]


def test_a_ctrl_c_lost_in_a_finaliser_stops_the_alternating_runs(lost_interrupt):
    """A Ctrl-C lost on the way (tests/conftest.py) stops the bench before its next timed run."""
    from reference.bench import _best_alternating
    from tracer import interrupt

    calls = []
    with pytest.raises(interrupt.Interrupted):
        _best_alternating({"a": (partial(calls.append, "a"), 3), "b": (lambda: 1.0, 3)})
    assert calls == []


def test_one_run_and_several_say_the_speed_in_the_same_words():
    # A single run (format_ratios()) and a summary of runs (format_summary()) word rtlab's
    # speed alike; below 1 it is a slow-down, its range turned round with it.
    assert speed_words(10.0, 10.0, 10.0, 1) == "rtlab is 10.00x faster"
    assert speed_words(10.0, 8.0, 12.0, 5) == "rtlab is 10.00x faster [8.00-12.00]"
    assert speed_words(0.8, 0.7, 0.9, 5) == "rtlab is 1.25x slower [1.11-1.43]"
    assert speed_words(0.8, 0.8, 0.8, 1) == "rtlab is 1.25x slower"
