"""Bad input is reported as InputError with a message naming the problem (the CLI turns it into
exit 2); tolerable input (extra keys, empty optional columns) loads."""
import json
import shutil
from pathlib import Path

import pytest

from analysis.common.load import InputError, load_results, require_usable

FIXTURES = Path(__file__).parent / "fixtures"
HEADER = (FIXTURES / "analysis_threads" / "runs.csv").read_text().splitlines()[0]


def folder(tmp_path, runs_text, meta=None):
    (tmp_path / "runs.csv").write_text(runs_text)
    if meta is not None:
        (tmp_path / "meta.json").write_text(meta)
    return tmp_path


def test_fixture_loads_with_empty_hardware_counters_and_G():
    results = load_results(FIXTURES / "analysis_threads")
    assert len(results.runs) == 22
    assert results.runs["cycles"].isna().all()
    assert results.runs.loc[results.runs["engine"] == "brute", "G"].isna().all()
    assert results.cores == 2
    require_usable(results)


@pytest.mark.parametrize("runs_text,message", [
    ("", "is empty"),
    (HEADER + "\n", "no runs"),
    ("engine,N,T,wall_s\nbrute,10,1,1.0\n", "status"),
    ("engine,N,T,status,wall_s\nbrute,ten,1,ok,1.0\n", "column N, data row 1"),
    ("engine,N,T,status,wall_s\nbrute,10,1,ok,\n", "column wall_s"),
])
def test_bad_runs_csv(tmp_path, runs_text, message):
    with pytest.raises(InputError, match=message):
        load_results(folder(tmp_path, runs_text))


def test_missing_folder_and_missing_runs_csv(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        load_results(tmp_path / "nowhere")
    with pytest.raises(InputError, match="runs.csv not found"):
        load_results(tmp_path)


def test_no_T1_baseline_anywhere():
    results = load_results(FIXTURES / "analysis_no_baseline")
    with pytest.raises(InputError, match="no successful run at T=1"):
        require_usable(results)


def test_T1_runs_that_all_failed_are_no_baseline(tmp_path):
    text = ("engine,N,T,status,wall_s\nbrute,10,1,failed,\nbrute,10,1,timeout,600\n"
            "brute,10,2,ok,1.0\n")
    with pytest.raises(InputError, match="T=1"):
        require_usable(load_results(folder(tmp_path, text)))


def test_every_run_failed_is_said_in_a_sentence(tmp_path):
    text = ("engine,N,T,status,wall_s,error\nbrute,10,1,failed,,psim exited 2: bad N\n"
            "brute,10,2,failed,,\nbrute,20,1,timeout,,exceeded timeout_s = 1\n")
    with pytest.raises(InputError) as raised:
        require_usable(load_results(folder(tmp_path, text)))
    assert str(raised.value).endswith(
        "runs.csv has no successful run, so there is nothing to plot: 2 failed and 1 timeout "
        "(first error: psim exited 2: bad N)")
    text = "engine,N,T,status,wall_s\nbrute,10,1,crashed,\n"
    with pytest.raises(InputError, match=r"nothing to plot: 1 crashed$"):
        require_usable(load_results(folder(tmp_path, text)))


def test_meta_is_optional_but_must_be_json(tmp_path):
    text = "engine,N,T,status,wall_s\nbrute,10,1,ok,1.0\n"
    assert load_results(folder(tmp_path, text)).meta == {}
    with pytest.raises(InputError, match="not valid JSON"):
        load_results(folder(tmp_path, text, meta="{not json"))


def test_garbled_counter_is_a_warning_not_an_error(tmp_path, capsys):
    text = "engine,N,T,status,wall_s,cycles\nbrute,10,1,ok,1.0,<not supported>\n"
    results = load_results(folder(tmp_path, text))
    assert results.runs["cycles"].isna().all()
    assert "cycles" in capsys.readouterr().err


def test_declared_metrics_are_numbers_and_stage_columns_come_from_the_declaration(tmp_path):
    meta = {"declaration": {"engines": [{"name": "brute", "reference": True,
                                         "matches_reference": True, "uses": ["T"]}],
                            "metrics": [{"key": "fancy_s", "kind": "stage_time"},
                                        {"key": "dummy", "kind": "counter"}]}}
    text = "engine,N,T,status,wall_s,fancy_s,dummy\nbrute,10,1,ok,1.0,0.25,7\n"
    results = load_results(folder(tmp_path, text, meta=json.dumps(meta)))
    assert results.runs["dummy"].iloc[0] == 7.0 and results.runs["fancy_s"].iloc[0] == 0.25
    assert results.declaration.stage_columns == ["fancy_s"]
    assert results.declaration.reference == "brute"
    assert not results.declaration.uses("brute", "G")
    # without meta.json: no declaration, so no engine facts and no stage columns
    (tmp_path / "bare").mkdir()
    bare = load_results(folder(tmp_path / "bare", text))
    assert bare.declaration.stage_columns == [] and bare.declaration.exact_engines is None
