"""``python -m tracking``: the docs/formats.md contract end to end, the readers, and bad input (one line, exit 2,
nothing written)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from acousim.twin.video import VideoCamera
from cubedimer.dataset import LoadConfig, load_dataset, load_run
from tracking.cli import main

from .conftest import FPS, motion, render

CAM = VideoCamera(noise=0.02)
#: reading a short clip: no minimum number of periods, no glitch masking (the tracked values are compared as they are)
SHORT = LoadConfig(min_periods=0, glitches=None)


def _fail(argv, capsys):
    code = main(["track"] + [str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("error: ") and "\n" not in err
    return err


def test_a_tiff_that_records_its_settings_gives_run_csv_and_run_json(tmp_path, write_tiff, capsys):
    _, y, theta = motion(160, seed=41)
    lost = [40, 41]
    src = write_tiff("run07.tif", render(y, theta, CAM, seed=41, lost=lost), CAM)
    out = tmp_path / "out" / "run07.csv"
    assert main(["track", str(src), "--out", str(out)]) == 0
    text = out.read_text().splitlines()
    assert any(line.startswith("# units:") for line in text) and "t,y,theta" in text
    assert text[text.index("t,y,theta") + 1 + 40] == "0.020000000,,"  # a lost frame: empty values
    run = json.loads(out.with_suffix(".json").read_text())
    assert run["pixel_size_m"] == CAM.pixel_size and run["frame_rate_hz"] == FPS
    assert run["frames_measured"] == 158 and run["frames_not_measured"] == 2 and run["not_measured"] == {"corrupt": 2}
    assert run["y_origin"]["row_px"] == CAM.origin[1] and run["y_origin"]["from"] == "recorded in the file"
    assert len(run["quality"]["edge_rms_px"]) == 160 and run["quality"]["edge_rms_px"][40] is None
    assert 0 < run["noise_estimate"]["y_m"] < 1e-6 and 0 < run["noise_estimate"]["theta"] < 0.005
    assert (out.parent / "run07.frame.png").exists() and run["example_frame"]["file"] == "run07.frame.png"
    assert abs(run["calibration"]["side_length_m"] - 500e-6) < 5e-6  # the silhouette's area gives the side
    loaded = load_run(out, SHORT)  # the loader reads it (and fills the two missing frames)
    assert loaded.n_filled == 2


def test_origin_from_the_first_frames_when_the_file_records_none(tmp_path, write_tiff, capsys):
    n = 120
    _, y, theta = motion(n, seed=42)
    y[:50] = 0.0  # levitation before the drop
    src = write_tiff("rec.tif", render(y, theta, CAM, seed=42), CAM, record=False)
    out = tmp_path / "rec.csv"
    assert main(["track", str(src), "--out", str(out), "--fps", "2000", "--pixel-size", "1e-5"]) == 0
    run = json.loads(out.with_suffix(".json").read_text())
    assert abs(run["y_origin"]["row_px"] - CAM.origin[1]) < 0.02  # median of 50 frames of 0.01 px noise
    assert run["y_origin"]["from"].startswith("median centre-of-mass row of the 50 measured frames")


def test_folder_of_recordings_gives_a_dataset_the_loader_reads(tmp_path, write_tiff):
    # 0.3 s at 2000 fps holds 6.6 periods of the 22 Hz trap: enough for the loader's checks (5 periods)
    for k in (1, 2):
        _, y, theta = motion(600, seed=50 + k)
        write_tiff(f"run{k:02d}.tif", render(y, theta, CAM, seed=50 + k), CAM)
    (tmp_path / "notes.txt").write_text("not a recording")
    out = tmp_path / "tracked"
    assert main(["track", str(tmp_path), "--out", str(out), "--workers", "1"]) == 0
    ds = load_dataset(out, strict=True)
    assert [r.name for r in ds.runs] == ["run01.csv", "run02.csv"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["frame_rate_hz"] == FPS
    tr = meta["tracking"]
    assert tr["fraction_measured"] == 1.0 and tr["skipped"] == [] and len(tr["runs"]) == 2
    assert 0 < tr["noise_y_m"] < 1e-6 and 0 < tr["noise_theta"] < 0.005
    assert ds.meta["tracking"]["noise_theta"] == tr["noise_theta"]


def test_lossless_video_file_through_ffmpeg(tmp_path, capsys):
    import imageio_ffmpeg

    _, y, theta = motion(100, seed=43)
    frames = render(y, theta, CAM, seed=43)
    path = tmp_path / "clip.mkv"
    w = imageio_ffmpeg.write_frames(str(path), (CAM.width, CAM.height), pix_fmt_in="gray", pix_fmt_out="gray",
                                    codec="ffv1", fps=25, macro_block_size=1, output_params=["-loglevel", "error"])
    w.send(None)
    for f in frames:
        w.send(np.ascontiguousarray(f))
    w.close()
    out = tmp_path / "clip.csv"
    # the container's 25 fps is a playback rate, not the camera's: the frame rate must be given
    err = _fail([path, "--out", out, "--pixel-size", "1e-5"], capsys)
    assert "unknown frame rate" in err and not out.exists()
    assert main(["track", str(path), "--out", str(out), "--fps", "2000", "--pixel-size", "1e-5", "--origin-row",
                 str(CAM.origin[1])]) == 0
    run = load_run(out, SHORT)
    assert np.sqrt(np.mean((run.y - y) ** 2)) < 1e-6 and np.sqrt(np.mean((run.theta - theta) ** 2)) < 0.005


def test_folder_of_images_is_one_recording(tmp_path):
    import imageio.v3 as iio

    _, y, theta = motion(60, seed=44)
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(render(y, theta, CAM, seed=44)):
        iio.imwrite(folder / f"img{i}.png", f)  # natural order: img2 before img10
    out = tmp_path / "frames.csv"
    assert main(["track", str(folder), "--out", str(out), "--fps", "2000", "--pixel-size", "1e-5", "--origin-row",
                 str(CAM.origin[1])]) == 0
    run = load_run(out, SHORT)
    assert np.sqrt(np.mean((run.y - y) ** 2)) < 1e-6


@pytest.mark.parametrize("case", ["not a video", "text as tiff", "fake cine", "different sizes", "different sizes (tiff)",
                                  "no dimer",
                                  "unknown pixel size", "folder needs a directory"])
def test_bad_input_gets_one_line_exit_2_and_no_output(tmp_path, write_tiff, capsys, case):
    out = tmp_path / "out" / "run.csv"
    args = ["--fps", "2000", "--pixel-size", "1e-5"]
    if case == "not a video":
        src = tmp_path / "clip.mp4"
        src.write_text("this is not a video\n")
        err = _fail([src, "--out", out, *args], capsys)
        assert "not a video file" in err
    elif case == "text as tiff":
        src = tmp_path / "frames.tif"
        src.write_text("plain text\n")
        assert "not a readable TIFF" in _fail([src, "--out", out, *args], capsys)
    elif case == "fake cine":
        src = tmp_path / "shot.cine"
        src.write_bytes(b"\x00" * 64)
        assert "not a readable Phantom .cine file" in _fail([src, "--out", out, *args], capsys)
    elif case == "different sizes":
        import imageio.v3 as iio

        src = tmp_path / "imgs"
        src.mkdir()
        iio.imwrite(src / "a1.png", np.full((50, 60), 200, np.uint8))
        iio.imwrite(src / "a2.png", np.full((52, 60), 200, np.uint8))
        assert "frames of different sizes" in _fail([src, "--out", out, *args], capsys)
    elif case == "different sizes (tiff)":
        import tifffile

        src = tmp_path / "pages.tif"
        with tifffile.TiffWriter(src) as w:
            w.write(np.full((4, 50, 60), 200, np.uint8), photometric="minisblack")
            w.write(np.full((2, 52, 60), 200, np.uint8), photometric="minisblack")
        assert "frames of different sizes" in _fail([src, "--out", out, *args], capsys)
    elif case == "no dimer":
        rng = np.random.default_rng(0)
        src = write_tiff("empty.tif", np.clip(200 + 3 * rng.standard_normal((40, 150, 180)), 0, 255).astype(np.uint8), CAM)
        assert "no dimer found" in _fail([src, "--out", out], capsys)
    elif case == "unknown pixel size":
        _, y, theta = motion(30, seed=45)
        src = write_tiff("bare.tif", render(y, theta, CAM, seed=45), CAM, record=False)
        assert "unknown pixel size" in _fail([src, "--out", out, "--fps", "2000"], capsys)
    else:
        _, y, theta = motion(30, seed=46)
        write_tiff("r1.tif", render(y, theta, CAM, seed=46), CAM)
        write_tiff("r2.tif", render(y, theta, CAM, seed=47), CAM)
        assert "give --out DIR" in _fail([tmp_path, "--out", out], capsys)
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_phantom_cine_records_its_frame_rate(tmp_path):
    from .cine_file import write_cine

    _, y, theta = motion(80, seed=48)
    src = tmp_path / "shot.cine"
    write_cine(src, render(y, theta, CAM, seed=48), 2000.0)
    out = tmp_path / "shot.csv"
    assert main(["track", str(src), "--out", str(out), "--pixel-size", "1e-5", "--origin-row", str(CAM.origin[1])]) == 0
    info = json.loads(out.with_suffix(".json").read_text())
    assert info["format"] == "cine" and info["frame_rate_hz"] == 2000.0 and info["frame_rate_from"] == "recorded in the file"
    run = load_run(out, SHORT)
    assert np.sqrt(np.mean((run.y - y) ** 2)) < 1e-6 and np.sqrt(np.mean((run.theta - theta) ** 2)) < 0.005


@pytest.mark.parametrize("record", [True, False])
def test_inspect_reports_what_the_file_records_and_the_calibration(tmp_path, write_tiff, capsys, record):
    """``inspect`` reads, calibrates and writes nothing: the recorded settings (or what track will need), the
    detected polarity and the cube side from the silhouette (500 um cubes at 10 um/px: 50 px)."""
    _, y, theta = motion(60, seed=43)
    src = write_tiff("clip.tif", render(y, theta, CAM, seed=43), CAM, record=record)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["inspect", str(src)]) == 0
    out = capsys.readouterr().out
    assert "60 frames" in out and "polarity: dark cubes (detected)" in out
    if record:
        assert f"{FPS:g} frames/s (recorded in the file)" in out and "levitation row" in out
        side_um = float(out.split(" px = ")[1].split(" um")[0])
        assert abs(side_um - 500.0) <= 5.0  # the same 1 % as the tracked run's side (test above)
    else:
        assert "not recorded: give track --fps" in out and "not recorded: give track --pixel-size" in out
    side_px = float(out.split("a cube side of ")[1].split(" px")[0])
    assert abs(side_px - 50.0) <= 0.5
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_inspect_refuses_a_missing_file(tmp_path, capsys):
    code = main(["inspect", str(tmp_path / "none.tif")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err == f"error: {tmp_path / 'none.tif'}: does not exist"


def test_a_recording_given_without_a_command_names_the_command(tmp_path, write_tiff, capsys):
    _, y, theta = motion(20, seed=44)
    src = write_tiff("old_style.tif", render(y, theta, CAM, seed=44), CAM)
    assert main([str(src), "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"python -m tracking track {src}" in err
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize("roi, message", [("0:200,0:150", "reaches outside the frames of 180 x 150 px"),
                                          ("50:40,0:150", "empty or inverted"), ("0-180,0-150", "expected x0:x1,y0:y1"),
                                          ("0:180,100:100", "empty or inverted")])
def test_a_bad_region_of_interest_gets_one_line_exit_2_and_no_output(tmp_path, write_tiff, capsys, roi, message):
    _, y, theta = motion(30, seed=48)
    src = write_tiff("r.tif", render(y, theta, CAM, seed=48), CAM)
    out = tmp_path / "out" / "run.csv"
    err = _fail([src, "--out", out, "--roi", roi], capsys)
    assert message in err
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_inspect_prints_the_file_facts_before_refusing_a_file_without_dimer(tmp_path, write_tiff, capsys):
    rng = np.random.default_rng(1)
    # one dark bead (a disc of 12 px radius) on the background: no dimer
    vv, uu = np.mgrid[:150, :180]
    bead = np.where((uu - 90) ** 2 + (vv - 75) ** 2 < 144, 40.0, 200.0)
    frames = np.clip(bead + 3 * rng.standard_normal((40, 150, 180)), 0, 255).astype(np.uint8)
    src = write_tiff("bead.tif", frames, CAM)
    assert main(["inspect", str(src)]) == 2
    cap = capsys.readouterr()
    assert "40 frames of 180 x 150 px" in cap.out and "frame rate: 2000 frames/s" in cap.out
    assert "no dimer found" in cap.err and len(cap.err.strip().splitlines()) == 1


def test_inspect_names_a_tilted_hinge_line(tmp_path, write_tiff, capsys):
    from acousim.twin.imperfections import Imperfections
    from acousim.twin.video import VideoCamera, record_video

    cam = VideoCamera(imperfections=Imperfections(tilt_deg=10.0))
    _, y, theta = motion(40, seed=49)
    src = write_tiff("tilted.tif", record_video(np.arange(40) / 2000.0, y, theta, 500e-6, cam, 49)[0], cam)
    assert main(["inspect", str(src)]) == 0
    out = capsys.readouterr().out
    assert "hinge line: tilted about" in out
    side = float(out.split("the side corrected for it is ")[1].split(" px")[0])
    assert abs(side / 50.0 - 1) < 0.03  # 500 um at 10 um/px; uncorrected it reads 11 % larger
