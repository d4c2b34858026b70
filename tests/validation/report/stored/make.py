"""Make the stored results the report's sentence tests read (``python tests/validation/report/stored/make.py``).

For each case of ``test_true_sentences.CASES``: the twin data set of its configuration, the whole report
(``build_report``, max_evals 60, one worker), and its stored results copied here, compact: ``<case>/diagnosis.json``,
``<case>/fit/model.json`` and ``<case>/fit/variant.json`` (when the model has cross-coupling terms).  The tests make
the report again from them (``render_report``) with the same twin data set, regenerated from the configuration.
Run it again when diagnosis.json or model.json change layout.
"""
import importlib.util
import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _cases():
    spec = importlib.util.spec_from_file_location("true_sentences", HERE.parent / "test_true_sentences.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.CASES, module._twin_config


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
    main(sys.argv[1:])
