"""``python3 -m validation.bench`` / ``ffrmbs bench``: runs the chosen benchmarks in one process
and writes well-formed JSON (no timing assertions). The peer benchmarks are checked here
only for their "not installed" rows; tests/integration/test_bench_peers.py runs them."""

import json
import subprocess
import sys

import pytest

from ffrmbs_app import cli
from validation.bench import ffr_evaluation, runner
from validation.bench import point_mass_beam as pmb_bench

SUMMARY_KEYS = {"module", "status", "wall_s", "verdicts"}


@pytest.fixture
def tiny_point_mass_beam(monkeypatch, tmp_path):
    """The point-mass benchmark at its smallest (two coarse meshes, 11 ms, 4 mode rows), its
    body data cached under tmp_path."""
    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(pmb_bench, "MODE_CONFIGS", [(10, "2s", "moreau", False), (20, "2s", "moreau", False),
                                                    (20, "2s", "moreau", True), (20, "2s", "moreau-adaptive", False)])
    monkeypatch.setattr(pmb_bench, "QUICK", {"repeats": 1, "node_repeats": 1, "t_end": 0.011, "node_t_end": 0.011,
                                             "divisions": ((10, 4, 4), (12, 4, 4))})


def test_quick_run_of_cheap_benches_writes_summary_and_one_json_each(tiny_point_mass_beam, tmp_path, capsys):
    out = tmp_path / "bench"
    summary = runner.run_benchmarks(str(out), quick=True, only=["ffr_evaluation", "point_mass_beam"])
    saved = json.loads((out / "summary.json").read_text())
    assert saved["quick"] is True and "machine" in saved
    assert list(saved["benches"]) == ["ffr_evaluation", "point_mass_beam"] == list(summary["benches"])
    printed = capsys.readouterr().out
    for name, entry in saved["benches"].items():
        assert SUMMARY_KEYS <= set(entry) and entry["status"] == "ok" and entry["wall_s"] > 0
        doc = json.loads((out / f"{name}.json").read_text())
        assert entry["json"] == str(out / f"{name}.json")
        assert isinstance(doc["table"], str) and isinstance(doc["rows"], list) and doc["rows"]
        assert f"## {name}" in printed and doc["table"] in printed
    pmb = json.loads((out / "point_mass_beam.json").read_text())
    assert {r["sweep"] for r in pmb["rows"]} == {"modes", "nodes"}
    assert not any(r["cached"] for r in pmb["rows"] if r["sweep"] == "nodes")      # preprocessed in tmp_path
    assert saved["benches"]["point_mass_beam"]["verdicts"] == pmb["verdicts"]


def test_missing_failing_and_malformed_benches_are_reported_not_raised(monkeypatch, tmp_path):
    monkeypatch.setitem(runner.BENCHES, "ghost", "validation.bench.no_such_benchmark")

    def boom(quick):
        raise RuntimeError("kaput")

    monkeypatch.setattr(ffr_evaluation, "run", boom)
    monkeypatch.setattr(pmb_bench, "run", lambda quick: {"rows": []})
    summary = runner.run_benchmarks(str(tmp_path), quick=True, only=["ghost", "ffr_evaluation", "point_mass_beam"])
    benches = json.loads((tmp_path / "summary.json").read_text())["benches"]
    assert benches == json.loads(json.dumps(summary["benches"]))
    assert benches["ghost"]["status"] == "not available"
    assert benches["ffr_evaluation"]["status"] == "failed" and "kaput" in benches["ffr_evaluation"]["error"]
    assert "RuntimeError" in benches["ffr_evaluation"]["traceback"]
    assert benches["point_mass_beam"]["status"] == "failed" and "'table'" in benches["point_mass_beam"]["error"]
    assert not (tmp_path / "ffr_evaluation.json").exists()


def test_peers_not_installed_give_skipped_rows(monkeypatch, tmp_path):
    from validation.peers import akantu_dynamics, exudyn_ffr

    monkeypatch.setattr(akantu_dynamics, "available", lambda: False)
    monkeypatch.setattr(exudyn_ffr, "available", lambda: False)
    summary = runner.run_benchmarks(str(tmp_path), quick=True, only=["akantu_case_study", "exudyn_free_flight"])
    for name, peer in (("akantu_case_study", "akantu"), ("exudyn_free_flight", "exudyn")):
        entry = summary["benches"][name]
        doc = json.loads((tmp_path / f"{name}.json").read_text())
        assert entry["status"] == "skipped" and f"skipped: {peer} not installed" in entry["skipped"]
        assert doc["rows"] == [] and f"skipped: {peer} not installed" in doc["table"]
        assert len(entry["verdicts"]) == 1 and "not installed" in entry["verdicts"][0]


def test_cli_bench_runs_one_benchmark(tmp_path, capsys):
    assert cli.main(["bench", "--quick", "--only", "ffr_evaluation", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert list(summary["benches"]) == ["ffr_evaluation"] and (tmp_path / "ffr_evaluation.json").is_file()
    assert "## ffr_evaluation" in capsys.readouterr().out


def test_unknown_name_is_one_line_listing_the_choices(tmp_path):
    res = subprocess.run([sys.executable, "-m", "validation.bench", "--only", "nonsense,point_mass_beam",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "nonsense" in res.stderr and "point_mass_beam" in res.stderr and "exudyn_free_flight" in res.stderr
    assert not (tmp_path / "summary.json").exists()


def test_split_names():
    assert runner.split_names(None) is None
    assert runner.split_names(["a,b", "c", " d , "]) == ["a", "b", "c", "d"]
