"""``python -m validation``: outputs checked before computing, meta.json errors, the same executor options
on every parallel command, and a blind study identical serially, on local processes and on a cluster."""
import shutil

import pytest

from validation.cli import main


def _one_line_error(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1, err
    return err[0]


@pytest.fixture
def tiny_data(tmp_path, sine_run, write_csv):
    data = tmp_path / "data"
    data.mkdir()
    write_csv(data / "run01.csv", *sine_run)
    return data


@pytest.mark.parametrize("meta, fragment", [
    ('{"side_length_m": -5e-4}', "side_length_m = -0.0005 is outside the plausible range"),
    ('{"side_length_m": false}', "side_length_m must be a number"),
    ('{"pressure_amplitude_pa": 1e300}', "pressure_amplitude_pa = 1e+300 is outside the plausible range"),
])
def test_diagnose_refuses_bad_meta_json_naming_it(tmp_path, tiny_data, capsys, meta, fragment):
    (tiny_data / "meta.json").write_text(meta)
    assert main(["diagnose", str(tiny_data), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    line = _one_line_error(capsys)
    assert "meta.json" in line and fragment in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["compare", "diagnose", "report", "blind"])
def test_unwritable_out_is_refused_before_computing(tmp_path, tiny_data, capsys, command):
    """A path under a file cannot be created, even by root (who ignores permission bits)."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    target = str(blocker / "out")
    argv = {"compare": ["compare", "--model", str(tmp_path / "model.json"), "--data", str(tiny_data)],
            "diagnose": ["diagnose", str(tiny_data)],
            "report": ["report", str(tiny_data)],
            "blind": ["blind", "--cases", "1"]}[command]
    assert main([*argv, "--out", target]) == 2
    line = _one_line_error(capsys)
    assert line.startswith(f"error: --out {target}") and "not a directory" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "file"]


def test_blind_size_limits(tmp_path, capsys):
    assert main(["blind", "--cases", "100000", "--out", str(tmp_path / "b")]) == 2
    assert "--cases = 100,000 exceeds the limit" in _one_line_error(capsys)
    assert main(["blind", "--runs", "10", "--duration", "1e6", "--out", str(tmp_path / "b")]) == 2
    assert "frames per case" in _one_line_error(capsys)
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("command", ["diagnose", "report", "blind"])
def test_parallel_commands_take_the_shared_executor_options(capsys, command):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    text = capsys.readouterr().out
    assert exc.value.code == 0 and "--workers N" in text and "--scheduler ADDRESS" in text


def _study_files(out):
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.suffix in (".json", ".md")}


@pytest.mark.slow
def test_blind_study_identical_serially_locally_and_on_a_cluster(tmp_path, process_cluster, capsys):
    """Each case simulates its runs inside its task (daemonic dask workers may not start a process
    pool); the study's files are byte-identical wherever the cases ran, and a study begun on local
    processes finishes on the cluster."""
    small = ["--runs", "3", "--duration", "2"]
    serial, mixed = tmp_path / "serial", tmp_path / "mixed"
    assert main(["blind", "--cases", "2", *small, "--workers", "1", "--out", str(serial)]) == 0
    # begun locally: one case (its runs simulated on 2 local processes), then finished on the cluster
    assert main(["blind", "--cases", "1", *small, "--workers", "2", "--out", str(mixed)]) == 0
    assert main(["blind", "--cases", "2", *small, "--scheduler", process_cluster,
                 "--out", str(mixed)]) == 0
    assert "resuming: 1 cases done, 1 to run" in capsys.readouterr().err
    reference = _study_files(serial)
    assert "cases/case001/result.json" in reference and "summary.json" in reference
    assert _study_files(mixed) == reference
    shutil.rmtree(serial)


def test_diagnose_refuses_a_negative_practical_threshold_in_one_line(tmp_path, tiny_data, capsys):
    assert main(["diagnose", str(tiny_data), "--out", str(tmp_path / "out"), "--min-improvement", "-0.1"]) == 2
    line = _one_line_error(capsys)
    assert line.startswith("error: ") and "min_relative_improvement" in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["diagnose", "report"])
def test_fullwave_model_refuses_another_experiment_in_one_line(tmp_path, tiny_data, capsys, command):
    """A dimer outside the full-wave family (1 mm at 45.65 kHz: ks = 0.84) is named with the range and the build
    command; nothing is written."""
    (tiny_data / "meta.json").write_text('{"side_length_m": 1e-3}')
    assert main([command, str(tiny_data), "--out", str(tmp_path / "out"), "--model", "fullwave", "--quiet"]) == 2
    line = _one_line_error(capsys)
    assert line.startswith("error: ") and "ks = 0.836" in line and "outside the full-wave family" in line
    assert "python -m acousim family build" in line
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.parametrize("command", ["diagnose", "report"])
def test_gap_with_the_gorkov_model_is_refused_in_one_line(tmp_path, tiny_data, capsys, command):
    assert main([command, str(tiny_data), "--out", str(tmp_path / "out"), "--gap", "5e-6", "--quiet"]) == 2
    line = _one_line_error(capsys)
    assert line == "error: --gap applies to --model fullwave only, not to --model gorkov"
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.parametrize("extra, says", [(["--heldout-tolerance", "1.5"], "needs a fraction in [0, 1)"),
                                         (["--heldout-tolerance", "0.002", "--method", "paper"],
                                          "applies to --method discovery")])
def test_report_heldout_tolerance_is_checked_before_anything_runs(tmp_path, tiny_data, capsys, extra, says):
    """A tolerance outside [0, 1), or with the paper's method, is one line naming the option; nothing is written."""
    assert main(["report", str(tiny_data), "--out", str(tmp_path / "out"), "--quiet", *extra]) == 2
    line = _one_line_error(capsys)
    assert line.startswith("error: --heldout-tolerance") and says in line
    assert not (tmp_path / "out").exists()


def _option_strings(parser, command):
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices[command]
    return {o for a in sub._actions for o in a.option_strings}


def test_the_report_offers_every_option_of_the_fit_with_the_same_help():
    """One options path (fitting.options): the report's fit options are the fit command's, help text included."""
    from fitting.cli import build_parser as fit_parser
    from validation.cli import build_parser as validation_parser

    fit_only = {"--out", "--strict", "--no-plots", "--quiet", "--workers", "--scheduler", "-h", "--help"}
    fit_options = _option_strings(fit_parser(), "fit") - fit_only
    assert {"--max-evals", "--joint-max-evals", "--output-error", "--selection", "--relative-threshold",
            "--no-glitch-mask", "--min-periods", "--heldout-tolerance", "--method"} <= fit_options
    assert fit_options <= _option_strings(validation_parser(), "report")

    def helps(parser, command):
        sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices[command]
        return {o: a.help for a in sub._actions for o in a.option_strings if o in fit_options}

    assert helps(fit_parser(), "fit") == helps(validation_parser(), "report")


def test_the_report_builds_its_fit_configuration_as_the_fit_command_does():
    """--max-evals sets the method's own refinement (the discovery's polish), --joint-max-evals the joint
    re-optimisation, and the loading options reach the loader, in both commands."""
    from fitting.cli import build_parser as fit_parser
    from fitting.options import fit_config_from_args
    from validation.cli import build_parser as validation_parser

    extra = ["--max-evals", "7", "--joint-max-evals", "9", "--output-error", "refine", "--no-glitch-mask",
             "--min-periods", "3", "--max-gap", "40"]
    fit_args = fit_parser().parse_args(["fit", "d", "--out", "o", *extra])
    report_args = validation_parser().parse_args(["report", "d", "--out", "o", *extra])
    cfg = fit_config_from_args(fit_args)
    assert cfg == fit_config_from_args(report_args)
    assert (cfg.method.polish.max_evals, cfg.method.joint.max_evals) == (7, 9)
    assert not hasattr(cfg.method, "refine")  # the paper's per-run refinement is not the discovery's setting
    assert cfg.method.selection.output_error.support_tolerance is None
    assert cfg.load.glitches is None and cfg.load.min_periods == 3.0 and cfg.load.max_gap == 40
    # not given: None, the data set's recorded fill limit or the loader's default
    assert fit_config_from_args(fit_parser().parse_args(["fit", "d", "--out", "o"])).load.max_gap is None


@pytest.mark.parametrize("extra, option", [
    (["--selection", "zscore"], "--selection"),  # the paper's rule, with the discovery
    (["--method", "paper", "--output-error", "off"], "--output-error"),
])
def test_report_refuses_a_fit_option_its_method_does_not_take_before_anything_runs(tmp_path, tiny_data, capsys,
                                                                                   extra, option):
    assert main(["report", str(tiny_data), "--out", str(tmp_path / "out"), "--quiet", *extra]) == 2
    assert _one_line_error(capsys).startswith(f"error: {option}")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["diagnose", "report"])
def test_a_single_run_is_refused_with_the_runs_needed(tmp_path, tiny_data, capsys, command):
    """One usable run: one line saying how many runs the diagnosis needs and why, exit 2, nothing written (the
    report refuses before its fit)."""
    out = tmp_path / "out"
    assert main([command, str(tiny_data), "--out", str(out), "--quiet"]) == 2
    line = _one_line_error(capsys)
    assert str(tiny_data) in line and "1 usable run;" in line
    assert "needs at least 3, because it scores every fit on runs held out of it" in line
    assert "at least 7 to name an effect at alpha 0.01" in line and "record more runs" in line
    assert not out.exists()


@pytest.mark.parametrize("command", ["diagnose", "report"])
@pytest.mark.parametrize("max_gap, runs", [([], "2 usable runs"), (["--max-gap", "50"], "1 usable run;")])
def test_max_gap_reaches_the_loader(tmp_path, sine_run, write_csv, capsys, command, max_gap, runs):
    """A 40-frame gap splits the run in two at the default fill limit (10 frames) and is filled under --max-gap 50:
    the runs the command counts (here refused as too few, before anything long runs) say which limit it loaded with."""
    data = tmp_path / "data"
    data.mkdir()
    t, y, th = sine_run
    y = y.copy()
    y[1000:1040] = float("nan")  # 40 frames: 2 % of the run, under the loader's 5 % of missing frames
    write_csv(data / "run01.csv", t, y, th)
    assert main([command, str(data), "--out", str(tmp_path / "out"), "--quiet", *max_gap]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("error: ") and runs in err[-1]
    assert ("split at 1 gap(s) longer than 10 missing frames" in err[0]) == (not max_gap)  # the split is said
