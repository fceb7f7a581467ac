"""evaluate, diagnose, simulate, calibrate: the CLI's figures, verdicts and files."""

import json
import os
import pathlib

import numpy as np
import pandas as pd
import pytest

import tcomp
from conftest import ROOT

EVAL_KEYS = ["samples", "raw_std", "residual_std", "raw_rms", "residual_rms", "max_abs_residual", "msd_after", "gaps", "input_faults"]


def test_evaluate_gives_the_figures_of_tcomp_eval_and_the_residual(ifog, ifog_model, cli, tmp_path):
    ifog_model.save(tmp_path / "m.tcm")
    e = ifog_model.evaluate(ifog.verify)
    p = cli(["eval", "--model", str(tmp_path / "m.tcm"), "--data", "verify.csv", "--json", "--quiet"], cwd=ifog.dir)
    theirs = json.loads(p.stdout)
    for k in EVAL_KEYS:
        assert e.figures[k] == theirs[k], k
    assert e.figures["binned"] == theirs["binned"]
    assert len(e.residual) == len(ifog.verify)
    # The residual is the one the figures are computed from.
    assert np.isclose(np.std(e.residual), e.figures["residual_std"], rtol=1e-12)
    assert abs(e.residual).max() == e.figures["max_abs_residual"]


def test_evaluate_takes_the_window_and_the_bin_and_refuses_a_bad_one(ifog, ifog_model):
    e = ifog_model.evaluate(ifog.verify, from_=1000.0, until=5000.0, bin=200)
    assert e.figures["samples"] == 4000 and e.figures["binned"]["seconds"] == 200
    with pytest.raises(tcomp.TcompError, match="--from 5000 must be less than --until 1000"):
        ifog_model.evaluate(ifog.verify, from_=5000.0, until=1000.0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'feature'"):
        ifog_model.evaluate(ifog.verify, feature="T")


def test_diagnose_returns_the_candidate_table_and_the_verdict_of_the_cli(ifog, cli, tmp_path):
    # The traditional model without the Shupe term: the diagnosis should name it.
    model = tcomp.fit(ifog.train, source="train.csv", target="gyro_dph", reference="ref_dph", signal="T=t_coil_c", feature=["T", "rate(T)"])
    model.save(tmp_path / "m.tcm")
    d = tcomp.diagnose(model, ifog.train, ifog.verify)
    assert isinstance(d.candidates, pd.DataFrame) and len(d.candidates) > 0
    assert {"change_pct"} <= set(d.candidates.columns)
    p = cli(["diagnose", "--model", str(tmp_path / "m.tcm"), "--data", "train.csv", "--verify", "verify.csv", "--json", "--quiet"], cwd=ifog.dir, timeout=900)
    theirs = json.loads(p.stdout)
    assert d.verdict == theirs["verdict"] and d.verdict_text == theirs["verdict_text"]
    assert [c["expr"] if "expr" in c else c.get("name") for c in d.raw["candidates"]] == [
        c["expr"] if "expr" in c else c.get("name") for c in theirs["candidates"]
    ]


def test_simulate_writes_what_the_cli_writes(tmp_path, cli):
    sim = tcomp.simulate("qma", out=tmp_path / "py", seed=3)
    cli(["simulate", "--preset", "qma", "--seed", "3", "--out", "cli", "--quiet"], cwd=tmp_path)
    for f in ["train.csv", "verify.csv", "truth.json"]:
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert list(sim.train.columns)[0] == "time_s" and len(sim.verify) > 0
    assert "qma" in tcomp.presets()
    with pytest.raises(tcomp.TcompError, match="unknown preset"):
        tcomp.simulate("no-such-preset", out=tmp_path / "x")


def test_calibrate_runs_the_spec_as_the_cli_does(tmp_path, cli):
    spec = ROOT / "data" / "realdata" / "mems_thermal_cycle.calibrate.toml"
    summary = tcomp.calibrate(spec, tmp_path / "py", diagnosis=False)
    cli(["calibrate", str(spec), "--out", str(tmp_path / "cli"), "--no-diagnosis", "--quiet"], cwd=tmp_path, timeout=900)
    theirs = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert summary == theirs
    # The blobs are the CLI's; the image too, but for its creation time (bytes 32–40) and the
    # whole-image CRC over it (bytes 12–16).
    blobs = sorted(p.name for p in (tmp_path / "cli").glob("*.tcm"))
    assert len(blobs) == 12  # each channel's model and its poly3 baseline
    for b in blobs:
        assert (tmp_path / "py" / b).read_bytes() == (tmp_path / "cli" / b).read_bytes(), b
    ours, cli_image = ((tmp_path / d / "image.bin").read_bytes() for d in ("py", "cli"))
    assert ours[:12] + ours[16:32] + ours[40:] == cli_image[:12] + cli_image[16:32] + cli_image[40:]
    with pytest.raises(tcomp.TcompError) as e:
        tcomp.calibrate(tmp_path / "missing.toml", tmp_path / "out")
    assert "missing.toml" in str(e.value)
