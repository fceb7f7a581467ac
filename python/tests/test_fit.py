"""fit: a Python fit is the CLI's fit, byte for byte; options are checked as the CLI checks them."""

import os
import threading

import numpy as np
import pandas as pd
import pytest

import tcomp
from conftest import IFOG_FIT


def cli_args(options):
    """The flags of `tcomp fit` for the keyword arguments `options`."""
    args = []
    for k, v in options.items():
        flag = "--" + k.rstrip("_").replace("_", "-")
        for item in v if isinstance(v, list) else [v]:
            args += [flag, str(item)]
    return args


@pytest.mark.parametrize(
    "reader",
    ["tcomp", "pandas"],
    ids=["read_csv of tcomp", "pandas read_csv"],
)
def test_a_python_fit_is_the_cli_fit_byte_for_byte(ifog, cli, tmp_path, reader):
    train = os.path.join(ifog.dir, "train.csv")
    data = tcomp.read_csv(train) if reader == "tcomp" else pd.read_csv(train)
    model = tcomp.fit(data, source="train.csv", **IFOG_FIT)
    cli(["fit", "--data", "train.csv", *cli_args(IFOG_FIT), "--out", str(tmp_path / "cli.tcm"), "--quiet"], cwd=ifog.dir)
    assert model.to_bytes() == (tmp_path / "cli.tcm").read_bytes()
    # The summary is the fit's: the model the CLI would report.
    assert model.summary["centers"] == 32
    assert model.features == IFOG_FIT["feature"]


def test_a_dict_of_arrays_fits_like_a_dataframe(ifog):
    as_dict = {c: ifog.train[c].to_numpy() for c in ifog.train.columns}
    a = tcomp.fit(ifog.train, **IFOG_FIT)
    b = tcomp.fit(as_dict, source="DataFrame", **IFOG_FIT)
    assert a == b


def test_model_bytes_round_trip_and_corruption_is_named(ifog_model, tmp_path):
    blob = ifog_model.to_bytes()
    assert tcomp.Model.from_bytes(blob) == ifog_model
    ifog_model.save(tmp_path / "m.tcm")
    assert tcomp.Model.load(tmp_path / "m.tcm").to_bytes() == blob
    bad = bytearray(blob)
    bad[len(bad) // 2] ^= 0x10
    with pytest.raises(tcomp.TcompError, match="checksum mismatch"):
        tcomp.Model.from_bytes(bytes(bad))
    assert ifog_model.info["unit"] == "deg/h" and ifog_model.unit == "deg/h"


def test_an_option_out_of_range_has_the_clis_message_and_names_the_option(ifog, cli, tmp_path):
    with pytest.raises(tcomp.TcompError) as e:
        tcomp.fit(ifog.train, target="gyro_dph", feature="T", average=-1)
    assert e.value.option == "average"
    spec = tmp_path / "s.toml"
    spec.write_text('target = "gyro_dph"\nfeature = ["T"]\naverage = -1\n')
    p = cli(["fit", "--data", "train.csv", "--spec", str(spec), "--out", str(tmp_path / "x.tcm")], cwd=ifog.dir, check=False)
    assert p.returncode == 1
    assert p.stderr.strip() == f"error: {e.value}"


def test_a_wrong_type_and_an_unknown_keyword_name_the_keyword(ifog):
    with pytest.raises(tcomp.TcompError, match="expected f64") as e:
        tcomp.fit(ifog.train, target="gyro_dph", feature="T", average="long")
    assert e.value.option == "average"
    with pytest.raises(tcomp.TcompError, match="unknown field `featuer`") as e:
        tcomp.fit(ifog.train, target="gyro_dph", featuer="T")
    assert e.value.option == "featuer"
    with pytest.raises(tcomp.TcompError, match="reference-value") as e:
        tcomp.fit(ifog.train, target="gyro_dph", feature="T", reference_value=float("nan"))
    assert e.value.option == "reference_value"


def test_a_bad_cell_is_named_by_line_and_column_as_in_the_csv(ifog, cli, tmp_path):
    # An infinite reading is refused under every --missing policy (a NaN or empty cell is a logger
    # dropout by default: its row is dropped and counted, see tcomp fit --missing).
    df = ifog.train.copy()
    df.loc[5, "t_coil_c"] = np.inf
    with pytest.raises(tcomp.TcompError) as e:
        tcomp.fit(df, source="bad.csv", **IFOG_FIT)
    assert (e.value.file, e.value.line, e.value.column) == ("bad.csv", 7, 3)
    # The same cell in a file: the CLI names the same line and column.
    df.to_csv(tmp_path / "bad.csv", index=False)
    p = cli(["fit", "--data", "bad.csv", "--target", "gyro_dph", "--reference", "ref_dph", "--signal", "T=t_coil_c", "--feature", "T", "--out", "x.tcm"], cwd=tmp_path, check=False)
    assert "bad.csv:7:3" in p.stderr and "bad.csv:7:3" in str(e.value)


def test_an_expression_error_points_into_the_expression(ifog):
    with pytest.raises(tcomp.TcompError, match=r"in `rate\(T`"):
        tcomp.fit(ifog.train, target="gyro_dph", signal="T=t_coil_c", feature="rate(T")


def test_the_gil_is_released_while_a_model_fits(ifog):
    """Another Python thread runs while the fit does (it would be blocked under the GIL)."""
    done = threading.Event()
    result = {}

    def work():
        result["model"] = tcomp.fit(ifog.train, method="gradient", iterations=400, **{k: v for k, v in IFOG_FIT.items() if k != "centers"})
        done.set()

    t = threading.Thread(target=work)
    t.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        done.wait(0.001)
    t.join()
    assert result["model"].to_bytes()
    assert ticks >= 5, f"the main thread ran {ticks} times during the fit"


def test_fit_keys_are_the_specs():
    keys = tcomp.fit_keys()
    for k in ["target", "feature", "signal", "average", "centers", "reference-value", "from", "power-on"]:
        assert k in keys
