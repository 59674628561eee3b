"""physid.sweep against `physid sweep`: shards, resume, the merged tables, progress and bad
inputs."""
import os
import subprocess

import pandas as pd
import pytest

import physid
from conftest import ROOT

BASE = os.path.join(ROOT, "scenarios", "sample_size.toml")


def sweep_file(d):
    p = d / "noise.toml"
    p.write_text(
        f'scenario = "{BASE}"\n[grid]\n"sensors.torque_noise" = [0.1, 0.5]\n'
        "[experiment]\nseeds = 2\nsizes = [30, 300]\nvalidation = 300\n"
        'constraints = ["none", "ellipsoid"]\n'
    )
    return str(p)


def test_shards_resume_and_merge_as_the_cli_does(tmp_path):
    s = sweep_file(tmp_path)
    seen = []
    first = physid.sweep(s, out=str(tmp_path / "py"), shard=(0, 2), threads=1, progress=lambda k, n: seen.append((k, n)))
    assert not first.merged and first.cells == {"total": 4, "shard": 2, "ran": 2, "missing": 2, "stale": 0}
    assert seen == [(1, 2), (2, 2)]
    with pytest.raises(ValueError, match="2 of 4 cells are still missing"):
        first.rows()
    # Without a shard: the finished cells are kept, the rest run, the tables merged.
    done = physid.sweep(s, out=str(tmp_path / "py"))
    assert done.merged and done.cells["ran"] == 2 and done.cells["missing"] == 0
    binary = os.environ.get("PHYSID_BIN")
    out = subprocess.run([binary, "sweep", s, "--out", str(tmp_path / "cli"), "--threads", "1"],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    for name, table in [("rows.csv", done.rows()), ("summary.csv", done.summary())]:
        cli = pd.read_csv(tmp_path / "cli" / name)
        written = pd.read_csv(tmp_path / "py" / name)
        timing = [c for c in cli.columns if c.startswith("solve_ms")]
        pd.testing.assert_frame_equal(table.drop(columns=timing), cli.drop(columns=timing))
        pd.testing.assert_frame_equal(table, written)
    assert len(done.rows()) == 2 * 2 * 2 * 2
    assert done.markdown == (tmp_path / "py" / "summary.md").read_text()
    # A third call has nothing to run.
    again = physid.sweep(s, out=str(tmp_path / "py"))
    assert again.cells["ran"] == 0 and again.merged


def test_bad_sweeps_are_named(tmp_path):
    s = sweep_file(tmp_path)
    with pytest.raises(ValueError, match=r"shard 2/2: need 0 <= K < N"):
        physid.sweep(s, out=str(tmp_path / "r"), shard=(2, 2))
    with pytest.raises(FileNotFoundError, match="missing.toml"):
        physid.sweep(str(tmp_path / "missing.toml"), out=str(tmp_path / "r"))
    bad = tmp_path / "bad.toml"
    bad.write_text(open(s).read().replace("[0.1, 0.5]", "[0.1, -1.0]"))
    with pytest.raises(ValueError, match="torque_noise"):
        physid.sweep(str(bad), out=str(tmp_path / "r2"))
    assert not (tmp_path / "r2").exists() or not any((tmp_path / "r2").rglob("*.parquet"))


def test_an_interrupted_sweep_writes_no_cell_after_and_does_not_merge(tmp_path):
    # Before: the abandoned sweep still ran every cell and merged the tables.
    import time

    from test_identify import physid_workers
    from test_simulate import interrupted

    # Cells of 40,000 samples each (a few seconds on one thread), so the interrupt lands
    # in the first.
    p = tmp_path / "long.toml"
    p.write_text(
        f'scenario = "{BASE}"\n[grid]\n"sensors.torque_noise" = [0.1, 0.5]\n'
        "[experiment]\nseeds = 2\nsizes = [30, 20000]\nvalidation = 20000\n"
        'constraints = ["none", "ellipsoid"]\n'
    )
    s = str(p)
    out = tmp_path / "res"

    def cells():
        return sorted(p.name for p in (out / "cells").glob("*.parquet"))

    interrupted(lambda: physid.sweep(s, out=str(out), threads=1), after=0.2)
    for _ in range(600):
        if not physid_workers():
            break
        time.sleep(0.05)
    assert physid_workers() == []
    written = len(cells())
    assert written < 4, cells()
    assert not (out / "rows.csv").exists() and not (out / "summary.md").exists()
    # Run again: the sweep resumes from the cells written, runs the rest and merges.
    done = physid.sweep(s, out=str(out), threads=1)
    assert done.merged and done.cells["ran"] == 4 - written


def test_progress_is_reported_in_order_on_the_calling_thread(tmp_path):
    import threading

    seen = []
    physid.sweep(sweep_file(tmp_path), out=str(tmp_path / "r"), threads=2,
                 progress=lambda k, n: seen.append((k, n, threading.get_ident())))
    assert [(k, n) for k, n, _ in seen] == [(1, 4), (2, 4), (3, 4), (4, 4)]
    assert {thread for *_, thread in seen} == {threading.get_ident()}


def test_a_failing_progress_callback_stops_the_sweep_at_once(tmp_path):
    import time

    from test_identify import physid_workers

    def boom(k, n):
        raise RuntimeError("enough")

    # Cells of 40,000 samples (a few seconds each on one thread): the report of the first
    # reaches the callback long before the last cell would end.
    p = tmp_path / "long.toml"
    p.write_text(
        f'scenario = "{BASE}"\n[grid]\n"sensors.torque_noise" = [0.1, 0.5]\n'
        "[experiment]\nseeds = 2\nsizes = [30, 20000]\nvalidation = 20000\n"
        'constraints = ["none", "ellipsoid"]\n'
    )
    out = tmp_path / "r"
    with pytest.raises(RuntimeError, match="enough"):
        physid.sweep(str(p), out=str(out), threads=1, progress=boom)
    for _ in range(600):
        if not physid_workers():
            break
        time.sleep(0.05)
    # The sweep stopped after the cell that reported: the rest not run, nothing merged.
    assert len(list((out / "cells").glob("*.parquet"))) < 4
    assert not (out / "rows.csv").exists()
