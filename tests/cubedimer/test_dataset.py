import json

import numpy as np
import pytest

from cubedimer.dataset import DEFAULT_MAX_GAP, DatasetError, LoadConfig, load_dataset, load_run


def test_good_file_with_comments_extra_columns_and_gaps(tmp_path, sine_run):
    t, y, th = sine_run
    y = y.copy()
    y[[100, 101, 102, 500]] = np.nan
    lines = ["# comment", "frame,theta,t,y"] + [f"{i},{c:.10g},{a:.10g},{'' if np.isnan(b) else f'{b:.10g}'}"
                                                 for i, (a, b, c) in enumerate(zip(t, y, th))]
    (tmp_path / "r.csv").write_text("\n".join(lines) + "\n")
    run = load_run(tmp_path / "r.csv")
    assert run.n_filled == 4
    # PCHIP across a 3-frame gap (span D = 4 ms) of a 22-Hz sine: error <= A (omega D)^2 / 8 = 3.8e-6 m
    np.testing.assert_allclose(run.y[100:103], 1e-4 * np.cos(2 * np.pi * 22 * t[100:103]),
                               atol=1e-4 * (2 * np.pi * 22 * 0.004) ** 2 / 8)


def _bad(tmp_path, sine_run, kind, write_csv):
    t, y, th = sine_run
    t, y, th = t.copy(), y.copy(), th.copy()
    p = tmp_path / f"{kind}.csv"
    if kind == "missing column":
        return write_csv(p, t, y, th, header="t,y,phi")
    if kind == "not strictly increasing":
        t[50] = t[49]
    elif kind == "not uniformly sampled":
        t[1000:] += 0.0005
    elif kind == "theta outside":
        th[10] = 1.2
    elif kind == "too short":
        t, y, th = t[:150], y[:150], th[:150]
    elif kind == "consecutive missing":
        y[100:140] = np.nan
    elif kind == "unreadable":
        p.write_bytes(b"\xff\xfe\x00garbage\x81")
        return p
    elif kind == "non-numeric":
        write_csv(p, t, y, th)
        p.write_text(p.read_text().replace(f"{y[5]:.10g}", "abc", 1))
        return p
    return write_csv(p, t, y, th)


@pytest.mark.parametrize("kind", ["missing column", "not strictly increasing", "not uniformly sampled",
                                  "theta outside", "too short", "consecutive missing", "unreadable",
                                  "non-numeric"])
def test_bad_input_one_line_error_naming_file(tmp_path, sine_run, kind, write_csv):
    p = _bad(tmp_path, sine_run, kind, write_csv)
    with pytest.raises(DatasetError) as err:
        load_run(p)
    msg = str(err.value)
    assert "\n" not in msg and p.name in msg
    key = {"unreadable": "unreadable", "non-numeric": "non-numeric"}.get(kind, kind)
    assert key.split()[0] in msg


def test_dataset_skips_bad_file_unless_strict(tmp_path, sine_run, write_csv):
    t, y, th = sine_run
    write_csv(tmp_path / "a.csv", t, y, th)
    write_csv(tmp_path / "b.csv", t, y, th + 2.0)
    msgs = []
    ds = load_dataset(tmp_path, report=msgs.append)
    assert [r.name for r in ds.runs] == ["a.csv"] and len(ds.skipped) == 1 and "b.csv" in msgs[0]
    with pytest.raises(DatasetError, match="b.csv"):
        load_dataset(tmp_path, strict=True)


def test_empty_dir_and_bad_meta(tmp_path, sine_run, write_csv):
    with pytest.raises(DatasetError, match="no CSV"):
        load_dataset(tmp_path)
    write_csv(tmp_path / "a.csv", *sine_run)
    (tmp_path / "meta.json").write_text('{"side_length_m": "big"}')
    with pytest.raises(DatasetError, match="meta.json"):
        load_dataset(tmp_path)


def test_byte_order_mark_is_read(tmp_path, sine_run, write_csv):
    """Spreadsheet programs write UTF-8 with a byte-order mark before the header."""
    p = write_csv(tmp_path / "bom.csv", *sine_run, comment=False)
    p.write_bytes(b"\xef\xbb\xbf" + p.read_bytes())
    run = load_run(p)
    np.testing.assert_allclose(run.y, sine_run[1], rtol=1e-9)


def test_error_line_numbers_are_file_lines(tmp_path, sine_run, write_csv):
    """Row 1002 of the data is line 1004 of the file (a comment line and the header come first)."""
    p = write_csv(tmp_path / "r.csv", *sine_run)
    lines = p.read_text().splitlines()
    assert lines[0].startswith("#") and lines[1] == "t,y,theta"
    lines[1003] = lines[1003].replace(",", ",abc,", 1).rsplit(",", 1)[0]  # file line 1004: y is 'abc'
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DatasetError, match=r"'abc'.* on line 1004$"):
        load_run(p)
    t = sine_run[0].copy()
    t[1001] = t[1000]  # data row 1002 repeats the time of row 1001
    write_csv(p, t, *sine_run[1:])
    with pytest.raises(DatasetError, match=r"not strictly increasing .*\(line 1004\)"):
        load_run(p)


def test_long_garbage_is_cut_in_the_message(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("x" * 20_000 + "\n1,2,3\n")
    with pytest.raises(DatasetError) as err:
        load_run(p)
    msg = str(err.value)
    # every missing column at once, and the header echo cut
    assert "missing columns 't', 'y', 'theta'" in msg and "\u2026" in msg
    # the 80-character echo plus the file name and the wording (which names the accepted columns and the docs)
    assert len(msg) < 80 + len(str(p)) + 260


def test_upper_case_suffix_is_a_csv_file(tmp_path, sine_run, write_csv):
    write_csv(tmp_path / "A.CSV", *sine_run)
    write_csv(tmp_path / "b.Csv", *sine_run)
    (tmp_path / "notes.txt").write_text("not a run")
    assert [r.name for r in load_dataset(tmp_path).runs] == ["A.CSV", "b.Csv"]


def test_missing_path_and_file_are_named_as_such(tmp_path, sine_run, write_csv):
    with pytest.raises(DatasetError, match="does not exist"):
        load_dataset(tmp_path / "nowhere")
    f = write_csv(tmp_path / "a.csv", *sine_run)
    with pytest.raises(DatasetError, match="not a directory"):
        load_dataset(f)


def test_skipped_files_are_logged_not_printed(tmp_path, sine_run, write_csv, capsys):
    import logging

    t, y, th = sine_run
    write_csv(tmp_path / "a.csv", t, y, th)
    write_csv(tmp_path / "b.csv", t, y, th + 2.0)
    records = []
    handler = logging.Handler()
    handler.emit = records.append
    log = logging.getLogger("cubedimer.dataset")
    log.addHandler(handler)
    try:
        ds = load_dataset(tmp_path)
    finally:
        log.removeHandler(handler)
    assert len(ds.runs) == 1
    assert [r.levelno for r in records] == [logging.WARNING] and "b.csv" in records[0].getMessage()
    assert capsys.readouterr().out == ""


def test_slow_drift_below_the_oscillation_is_not_taken_for_it(tmp_path, write_csv):
    """A drift of the levitation height larger than the oscillation: the run holds enough periods
    of the oscillation, which the drift-robust rule finds above the min_periods frequency."""
    t = np.arange(2000) / 1000.0
    y = 2e-4 * t / t[-1] + 1e-4 * np.cos(2 * np.pi * 22 * t)
    run = load_run(write_csv(tmp_path / "d.csv", t, y, 0.1 * np.sin(2 * np.pi * 9 * t)))
    assert run.t.size == 2000


def test_a_drifting_pressure_with_a_decayed_oscillation_keeps_the_run(tmp_path, write_csv):
    """A 4 % pressure drift (period 2 s) moves the height by +-35 um, while the oscillation has decayed to 12 um:
    its spectral line is a sixth of the drift's.  The loader and the consistency check read the same run with the
    same rule (:data:`cubedimer.consistency.SLOW_PEAK_FRACTION`): the oscillation, not the drift, sets f_y, and
    the run is kept.  (With a loader threshold of 0.3, such runs of a drifting twin were refused as too short.)"""
    from cubedimer.consistency import SLOW_PEAK_FRACTION, run_features
    from cubedimer.spectra import amplitude_spectrum

    t = np.arange(4500) / 1500.0
    y = 35e-6 * np.sin(2 * np.pi * t / 2.0 + 0.4) + 12e-6 * np.exp(-0.5 * t) * np.cos(2 * np.pi * 21.0 * t)
    f, a = amplitude_spectrum(y, t[1])
    a[0] = 0.0
    line_over_drift = a[f >= 5 / 3].max() / a.max()
    assert SLOW_PEAK_FRACTION < line_over_drift < 0.3  # the case this test is about
    run = load_run(write_csv(tmp_path / "drift.csv", t, y, 0.1 * np.sin(2 * np.pi * 9 * t)))
    assert run.t.size == t.size
    assert run_features("drift.csv", t, y).f_y == pytest.approx(21.0, abs=0.1)


def _noisy_runs(n, seed, duration=3.0, fps=1500.0):
    """n decaying 21.8-Hz runs with 1.5 um / 0.003 tracking noise, as (t, y, theta)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fps)) / fps
    out = []
    for _ in range(n):
        a, b = rng.uniform(5e-5, 3e-4), rng.uniform(0.05, 0.3)
        y = a * np.exp(-0.3 * t) * np.cos(2 * np.pi * 21.8 * t + rng.uniform(0, 6)) + 1.5e-6 * rng.standard_normal(t.size)
        th = b * np.cos(2 * np.pi * 9.0 * t + rng.uniform(0, 6)) + 0.003 * rng.standard_normal(t.size)
        out.append((t, y, th))
    return out


def test_tracking_glitches_are_masked_and_counted(tmp_path, write_csv):
    (t, y, th), = _noisy_runs(1, 4)
    clean = y.copy()
    idx = np.array([100, 900, 1700, 2500, 3300, 4100])
    y = y.copy()
    y[idx] += 100 * 1.5e-6  # 100 times the tracking noise
    run = load_run(write_csv(tmp_path / "g.csv", t, y, th))
    assert run.glitch_frames == tuple(idx) and run.n_glitches == 6
    # a masked frame is interpolated from its neighbours: within a few noise levels of the clean value
    np.testing.assert_allclose(run.y[idx], clean[idx], atol=5 * 1.5e-6)
    assert load_run(write_csv(tmp_path / "c.csv", t, clean, th)).n_glitches == 0


@pytest.mark.parametrize("n_runs", [4, 12])
def test_a_file_in_milliseconds_is_skipped_with_its_cause(tmp_path, write_csv, n_runs):
    for i, (t, y, th) in enumerate(_noisy_runs(n_runs, n_runs), 1):
        write_csv(tmp_path / f"run{i:02d}.csv", 1e3 * t if i == 2 else t, y, th)
    ds = load_dataset(tmp_path)
    assert [r.name for r in ds.runs] == [f"run{i:02d}.csv" for i in range(1, n_runs + 1) if i != 2]
    (entry,) = ds.skipped_files()
    assert entry["file"] == "run02.csv" and entry["reason"].startswith("t looks like milliseconds")
    with pytest.raises(DatasetError, match="run02.csv: t looks like milliseconds"):
        load_dataset(tmp_path, strict=True)


def test_meta_plausibility_names_a_micrometre_file_even_alone(tmp_path, write_csv):
    (t, y, th), = _noisy_runs(1, 8)
    write_csv(tmp_path / "um.csv", t, 1e6 * y, th)
    (tmp_path / "meta.json").write_text('{"side_length_m": 5e-4, "pressure_amplitude_pa": 3000}')
    with pytest.raises(DatasetError, match="no usable runs"):
        load_dataset(tmp_path)
    with pytest.raises(DatasetError, match="um.csv: y amplitude .* quarter wavelength .*micrometres"):
        load_dataset(tmp_path, strict=True)


def test_a_run_that_still_holds_its_field_drop_is_cut_at_the_return(tmp_path, write_csv, drop_heights, caplog):
    rng = np.random.default_rng(4)
    t, y, on = drop_heights(3000, 2000.0, 59.6, 3.5e-3)
    th = 0.2 * np.sin(2 * np.pi * 3.1 * t)
    run = load_run(write_csv(tmp_path / "drop.csv", t, y + 0.2e-6 * rng.standard_normal(t.size), th))
    first = 3000 - run.t.size
    assert on - 1 <= first <= on + 5  # the rest and the fall left out (tests/cubedimer/test_drop_phases.py)
    assert run.n_glitches == 0 and "cut at the field's return" in caplog.text


def test_rest_frames_then_a_jump_are_refused_in_one_line(tmp_path, write_csv):
    t = np.arange(3000) / 2000.0
    y = np.where(t < 0.03, 0.0, -8e-5 * np.cos(2 * np.pi * 22 * (t - 0.03)))
    y = y + 0.2e-6 * np.random.default_rng(3).standard_normal(t.size)
    with pytest.raises(DatasetError, match=r"jump.csv: starts with \d+ frames at rest and then .*cut the file"):
        load_run(write_csv(tmp_path / "jump.csv", t, y, 0.1 * np.sin(2 * np.pi * 3 * t)))


@pytest.mark.parametrize("gap_at, kept", [(1500, 2), (150, 1)])
def test_a_long_gap_splits_the_run_and_a_short_part_is_dropped(tmp_path, write_csv, gap_at, kept):
    # 4 s at 1500 fps of a 21.8-Hz run with a 200-frame gap: split into two parts; a part of 150 frames
    # (0.1 s, 2.2 periods) is below the 5 periods a run needs and is skipped with its reason, the other kept
    (t, y, th), = _noisy_runs(1, 21, duration=4.0)
    y, th = y.copy(), th.copy()
    y[gap_at:gap_at + 200] = np.nan
    th[gap_at:gap_at + 200] = np.nan
    write_csv(tmp_path / "run03.csv", t, y, th)
    for i in (1, 2):  # the consistency check needs company
        (t2, y2, th2), = _noisy_runs(1, 30 + i, duration=4.0)
        write_csv(tmp_path / f"run0{i}.csv", t2, y2, th2)
    ds = load_dataset(tmp_path)
    parts = [r for r in ds.runs if r.source == "run03.csv"]
    assert len(parts) == kept
    assert parts[-1].frames == (gap_at + 200, t.size) and parts[-1].name.startswith("run03_part")
    if kept == 1:
        (entry,) = ds.skipped_files()
        assert entry["file"] == "run03_part1.csv" and "oscillation periods" in entry["reason"]
    else:
        assert parts[0].frames == (0, gap_at) and not ds.skipped


def test_a_tracked_set_s_recorded_fill_limit_is_the_loader_s(tmp_path, write_csv):
    # a 40-frame gap: split at the default limit of 10, filled under the set's recorded 50 (tracking track --max-gap)
    (t, y, th), = _noisy_runs(1, 21, duration=4.0)
    y = y.copy()
    y[3000:3040] = np.nan
    write_csv(tmp_path / "run01.csv", t, y, th)
    assert [r.name for r in load_dataset(tmp_path, config=LoadConfig(consistency=None)).runs] == [
        "run01_part1.csv", "run01_part2.csv"]
    (tmp_path / "meta.json").write_text('{"tracking": {"max_gap_frames": 50}}')
    (run,) = load_dataset(tmp_path, config=LoadConfig(consistency=None)).runs
    assert run.name == "run01.csv" and run.n_filled == 40


def test_a_fill_limit_the_caller_gives_overrides_the_recorded_one(tmp_path, write_csv):
    # meta.json records 50 frames; the caller's 10 (--max-gap 10, the default's value) is used all the same
    (t, y, th), = _noisy_runs(1, 21, duration=4.0)
    y = y.copy()
    y[3000:3040] = np.nan
    write_csv(tmp_path / "run01.csv", t, y, th)
    (tmp_path / "meta.json").write_text('{"tracking": {"max_gap_frames": 50}}')
    assert LoadConfig().max_gap is None and LoadConfig().fill_limit == DEFAULT_MAX_GAP == 10
    runs = load_dataset(tmp_path, config=LoadConfig(consistency=None, max_gap=10)).runs
    assert [r.name for r in runs] == ["run01_part1.csv", "run01_part2.csv"]


def test_each_run_carries_the_noise_the_tracking_recorded_for_it(tmp_path, write_csv):
    # meta.json's tracking.runs[] (tracking track writes each run's own noise): read per file; a part of a run split
    # at a long gap has its file's; a file without a usable record has none
    runs = _noisy_runs(3, 21, duration=4.0)
    y = runs[1][1].copy()
    y[3000:3040] = np.nan
    for i, (t, yy, th) in enumerate(runs, 1):
        write_csv(tmp_path / f"run{i:02d}.csv", t, y if i == 2 else yy, th)
    (tmp_path / "meta.json").write_text(json.dumps({"tracking": {"noise_y_m": 2e-7, "noise_theta": 1e-3, "runs": [
        {"file": "run01.csv", "noise_y_m": 1e-7, "noise_theta": 5e-4},
        {"file": "run02.csv", "noise_y_m": 3e-7, "noise_theta": 2e-3},
        {"file": "run03.csv", "noise_y_m": 0.0, "noise_theta": 2e-3}]}}))
    ds = load_dataset(tmp_path, config=LoadConfig(consistency=None))
    assert {r.name: r.noise for r in ds.runs} == {"run01.csv": (1e-7, 5e-4), "run02_part1.csv": (3e-7, 2e-3),
                                                  "run02_part2.csv": (3e-7, 2e-3), "run03.csv": None}
    (tmp_path / "meta.json").write_text("{}")
    assert all(r.noise is None for r in load_dataset(tmp_path, config=LoadConfig(consistency=None)).runs)
