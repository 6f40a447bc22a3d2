"""SPI faults on the texture rig's bus declared where sweeps and experiments are set up (texture-sweep --spi-fault,
an experiment file's ``[rig] spi_faults``), validated as every other field, and the samples the host rejected
counted in every trial row (``rejected_samples``: trials.csv, trials.json and the stage cache)."""

import csv
import json
from dataclasses import asdict

import pytest

from bench.cli import main as cli
from bench.experiments import experiment as E
from bench.experiments.trials import TrialTask, sweep_tasks
from bench.reporting.trials_file import read_trials
from bench.rigs.texture_rig import SpiFaultWindow, movement_grid, spi_fault_text, spi_faults_from_text
from emulator import channels as ch
from emulator.spi.model import Faults

pytestmark = pytest.mark.unit

#: MISO's second bit inverted while the finger is still in the air (0.25–0.35 s): every word there fails its parity
WINDOW = "start_s=0.25,end_s=0.35,miso_flip_bit=1"


def test_a_sweep_with_an_spi_fault_counts_the_rejected_samples_in_its_rows(tmp_path):
    """texture-sweep --spi-fault: the trial runs with the fault on the bus, and its row in trials.csv and trials.json
    says which faults and how many samples the host rejected — every slot of the 0.1 s window, whatever its channel."""
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--textures", "100", "--movements", "14", "--trials", "1", "--workers", "1",
                     "--spi-fault", WINDOW, "--out", str(out), "--quiet"]) == 0
    (row,) = csv.DictReader(open(out / "trials.csv"))
    (doc_row,) = read_trials(out / "trials.json")["rows"]
    slots = round(0.1 * ch.DEFAULT_SLOT_RATE_HZ)  # the window's slots: each one's word flagged bad
    assert (row["rejected_samples"], row["spi_faults"]) == (str(slots), WINDOW)
    assert (doc_row["rejected_samples"], doc_row["spi_faults"]) == (slots, WINDOW)


@pytest.mark.parametrize("given, message", [
    (["start_s=0.3,end_s=0.2,miso_flip_bit=1"], "--spi-fault[0].end_s = 0.2: must be after start_s = 0.3"),
    (["start_s=0.1,end_s=0.2,miso_flip_bit=16"],
     "--spi-fault[0].miso_flip_bit = 16: must be a bit position 0 to 15 (from chip-select fall)"),
    ([WINDOW, "start_s=0.1,end_s=0.2,miso_stuck=2"], "--spi-fault[1].miso_stuck = 2: must be 0 or 1"),
    (["start_s=-1,end_s=0.2,bad_parity=true"],
     "--spi-fault[0].start_s = -1: must be a number of seconds ≥ 0 from the trial's start"),
    (["start_s=0.1,end_s=0.2,slow_response=yes"], '--spi-fault[0].slow_response = "yes": must be true or false'),
    (["start_s=0.1,end_s=0.2"], "--spi-fault[0] = {start_s = 0.1, end_s = 0.2}: sets no fault; give at least one of "
                                "miso_flip_bit, mosi_flip_bit, miso_stuck, bad_parity, slow_response"),
    (["start_s=0.1,end_s=0.2,miso_flip=1"], '--spi-fault[0]: unknown field "miso_flip"; known: start_s, end_s, '
                                            "miso_flip_bit, mosi_flip_bit, miso_stuck, bad_parity, slow_response"),
    (["0.1-0.2"], '--spi-fault[0] = "0.1-0.2": "0.1-0.2" is no FIELD=VALUE; write start_s=S,end_s=S,SETTING=VALUE,'
                  "... (e.g. start_s=0.3,end_s=0.4,miso_flip_bit=1)"),
    ([WINDOW, ""], '--spi-fault[1] = "": declares no window; write start_s=S,end_s=S,SETTING=VALUE,... (e.g. '
                   "start_s=0.3,end_s=0.4,miso_flip_bit=1)"),
    ([" ; "], '--spi-fault[0] = " ; ": declares no window; write start_s=S,end_s=S,SETTING=VALUE,... (e.g. '
              "start_s=0.3,end_s=0.4,miso_flip_bit=1)"),
    ([WINDOW, "start_s=0.3,end_s=0.5,bad_parity=true"],
     "--spi-fault[1] (0.3 to 0.5 s) overlaps --spi-fault[0] (0.25 to 0.35 s): windows may not overlap (whose "
     "faults would be in force?)"),
])
def test_a_bad_spi_fault_option_is_one_line_naming_it_before_anything_runs(tmp_path, capsys, given, message):
    out = tmp_path / "sweep"
    argv = ["texture-sweep", "--textures", "100", "--movements", "14", "--trials", "1", "--out", str(out)]
    assert cli.main(argv + [arg for g in given for arg in ("--spi-fault", g)]) == 2
    assert capsys.readouterr().err == f"error: {message}\n"
    assert not out.exists()


def _experiment(rig: dict) -> E.ExperimentSpec:
    return E.parse_experiment({"experiment": {"name": "faulty"}, "rig": rig}, "faulty.toml")


def test_an_experiment_file_declares_spi_faults_for_every_trial(tmp_path):
    """[rig] spi_faults, as an array of tables in the file: the windows every trial of every stage runs with, in the
    form texture-sweep's rows show them (and read back to the same windows)."""
    path = tmp_path / "faulty.toml"
    path.write_text('[experiment]\nname = "faulty"\n[[rig.spi_faults]]\nstart_s = 0.25\nend_s = 0.35\n'
                    "miso_flip_bit = 1\n[[rig.spi_faults]]\nstart_s = 1\nend_s = 1.5\nbad_parity = true\n")
    spec = E.load_experiment(path)
    assert spec.spi_faults == "start_s=0.25,end_s=0.35,miso_flip_bit=1; start_s=1.0,end_s=1.5,bad_parity=true"
    assert spi_faults_from_text(spec.spi_faults, "x") == ((
        SpiFaultWindow(0.25, 0.35, Faults(miso_flip_bit=1)), SpiFaultWindow(1.0, 1.5, Faults(bad_parity=True))), [])
    assert _experiment({}).spi_faults == "" and _experiment({"spi_faults": []}).spi_faults == ""


@pytest.mark.parametrize("declared, problem", [
    ([{"start_s": 0.2, "end_s": 0.2, "miso_flip_bit": 1}], "rig.spi_faults[0].end_s = 0.2: must be after start_s = 0.2"),
    ([{"start_s": 0.1, "end_s": 0.2, "mosi_flip_bit": 1.5}],
     "rig.spi_faults[0].mosi_flip_bit = 1.5: must be a bit position 0 to 15 (from chip-select fall)"),
    ([{"end_s": 0.2, "miso_stuck": 0}], "rig.spi_faults[0].start_s is missing: a number of seconds ≥ 0 from the "
                                        "trial's start"),
    ([{"start_s": 0.1, "end_s": float("inf"), "miso_stuck": 0}],
     "rig.spi_faults[0].end_s = inf: must be a number of seconds ≥ 0 from the trial's start"),
    ({"start_s": 0.1, "end_s": 0.2, "miso_stuck": 0},
     "rig.spi_faults = {start_s = 0.1, end_s = 0.2, miso_stuck = 0}: a list of at most 100 windows, each a table of "
     "start_s and end_s (s from the trial's start, 0 ≤ start_s < end_s) and the faults in force then (miso_flip_bit, "
     "mosi_flip_bit, miso_stuck, bad_parity, slow_response)"),
    ([{"start_s": 0.1, "end_s": 0.2, "bad_parity": False}],
     "rig.spi_faults[0] = {start_s = 0.1, end_s = 0.2, bad_parity = false}: sets no fault; give at least one of "
     "miso_flip_bit, mosi_flip_bit, miso_stuck, bad_parity, slow_response"),
    ([{"start_s": 1, "end_s": 2, "bad_parity": True}, {"start_s": 0, "end_s": 1.5, "miso_stuck": 1}],
     "rig.spi_faults[0] (1 to 2 s) overlaps rig.spi_faults[1] (0 to 1.5 s): windows may not overlap (whose faults "
     "would be in force?)"),
])
def test_bad_spi_faults_in_an_experiment_file_name_field_value_and_what_is_allowed(declared, problem):
    with pytest.raises(E.ExperimentError) as e:
        _experiment({"spi_faults": declared})
    assert e.value.problems == [problem]


def test_every_stage_of_an_experiment_runs_its_trials_with_the_files_spi_faults(monkeypatch):
    """run_experiment hands [rig] spi_faults to every trial of the pilot, training and validation.  The trials'
    sliding is not what is tested here: the stages' tasks are taken as they reach the campaign engine and answered
    with rows whose properties tell the textures apart (so the stages and the exploration go on)."""
    spec = E.parse_experiment({"experiment": {"name": "faulty"}, "pilot": {"textures": [2, 3], "trials": 2,
                                                                           "movements": [0, 7, 14]},
                               "training": {"textures": [2, 3], "trials": 2}, "validation": {"pairs": [[2, 3]],
                                                                                             "trials": 1},
                               "exploration": {"pair_simulations": 2, "identification_simulations": 2},
                               "rig": {"spi_faults": [{"start_s": 0.25, "end_s": 0.35, "miso_flip_bit": 1}]}},
                              "faulty.toml")
    seen = []

    def answered(tasks, **_):
        seen.extend(tasks)
        return [dict(asdict(t), traction=t.texture + 0.1 * t.trial, roughness=t.texture - 0.1 * t.trial,
                     fineness=t.movement_id + t.texture + 0.1 * t.trial, pac_at_rails=0, rejected_samples=440)
                for t in tasks]

    monkeypatch.setattr(E, "sweep", answered)
    E.run_experiment(spec, cache_dir=None, progress=False, log=lambda m: None)
    assert {t.stage for t in seen} == {"pilot", "training", "validation"}
    assert {t.spi_faults for t in seen} == {WINDOW}


def test_a_cached_row_without_the_rejected_sample_count_is_run_again_not_read(tmp_path):
    """The stage cache holds each trial's row: one cached before the rows counted the rejected samples is refused
    (its trials run again), never read as a row with the count missing."""
    task = TrialTask(texture=46, force_N=0.2, velocity_m_per_s=0.01, trial=1, seed=5, movement_id=0, stage="pilot",
                     spi_faults=WINDOW)
    row = dict(asdict(task), traction=0.1, roughness=-6.9, fineness=5.5, pac_at_rails=0, rejected_samples=440)
    path = tmp_path / "pilot.json"
    path.write_text(json.dumps([row]))
    assert E._cached_rows(path, [task]) == ([row], "")
    old = dict(row)
    del old["rejected_samples"]
    path.write_text(json.dumps([old]))
    assert E._cached_rows(path, [task]) == (None, "a row without rejected_samples (cached before the rows had it)")


def test_sweep_tasks_carry_the_spi_faults_and_the_text_reads_back_to_the_same_windows():
    windows = (SpiFaultWindow(0.25, 0.35, Faults(miso_flip_bit=1)),
               SpiFaultWindow(0.5, 0.75, Faults(mosi_flip_bit=0, miso_stuck=0, slow_response=True)))
    text = spi_fault_text(windows)
    assert text == ("start_s=0.25,end_s=0.35,miso_flip_bit=1; start_s=0.5,end_s=0.75,mosi_flip_bit=0,miso_stuck=0,"
                    "slow_response=true")
    assert spi_faults_from_text(text, "x") == (windows, [])
    tasks = sweep_tasks([100], [movement_grid()[14]], 2, movement_ids=[14], spi_faults=text)
    assert [t.spi_faults for t in tasks] == [text, text]
