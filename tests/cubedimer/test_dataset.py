import numpy as np
import pytest

from cubedimer.dataset import DatasetError, load_dataset, load_run


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
