"""Make the stored results the report's tests read (``python tests/validation/report/stored/make.py [CASE ...]``,
and ``... make.py --diagnoses [CASE ...]``).

For each case of ``STORED_CASES`` (tests/validation/report/conftest.py; the names given, or all): the twin data set of
its configuration, the whole report (``build_report``, max_evals 60, one worker), and its stored results copied here,
compact: ``<case>/diagnosis.json``, ``<case>/fit/model.json`` and ``<case>/fit/variant.json`` (when the model has
cross-coupling terms).  The tests make the report again from them (``render_report``) with the same twin data set,
regenerated from the configuration.  With ``--diagnoses``: the diagnoses of ``test_true_sentences.DIAGNOSIS_CASES``,
``diagnosed/<case>.json``.  Run it again when diagnosis.json or model.json change layout.
"""
import importlib.util
import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _module(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _cases():
    module = _module("report_conftest", HERE.parent / "conftest.py")
    return module.STORED_CASES, module.stored_twin_config


def diagnoses(names=None) -> None:
    """The stored diagnoses of ``test_true_sentences.DIAGNOSIS_CASES`` (the names given, or all):
    ``diagnosed/<case>.json``."""
    module = _module("true_sentences", HERE.parent / "test_true_sentences.py")
    for name in names or module.DIAGNOSIS_CASES:
        with tempfile.TemporaryDirectory() as tmp:
            diag = module.make_diagnosis(name, Path(tmp))
        out = HERE / "diagnosed" / f"{name.replace(' ', '_')}.json"
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(diag.to_json(), separators=(",", ":")) + "\n")
        print("stored", out)


def main(names=None) -> None:
    from acousim.twin import simulate_dataset
    from validation.report import build_report

    cases, twin_config = _cases()
    for name in names or cases:
        runs, duration, effects = cases[name]
        with tempfile.TemporaryDirectory() as tmp:
            data = Path(tmp) / "data"
            simulate_dataset(twin_config(runs, duration, effects), data, progress=False)
            build_report(data, Path(tmp) / "report", workers=1, progress=False, max_evals=60)
            out = HERE / name.replace(" ", "_")
            for rel in ("diagnosis.json", "fit/model.json", "fit/variant.json"):
                src = Path(tmp) / "report" / rel
                if src.exists():
                    (out / rel).parent.mkdir(parents=True, exist_ok=True)
                    (out / rel).write_text(json.dumps(json.loads(src.read_text()), separators=(",", ":")) + "\n")
        print("stored", out)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--diagnoses"]:
        diagnoses(sys.argv[2:])
    else:
        main(sys.argv[1:])
