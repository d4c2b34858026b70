"""cubedimer: the shared core of the cube-dimer suite.

What more than one of the user-facing packages (``acousim``, ``fitting``, ``validation``, ``tracking``) needs lives
here, so that ``acousim`` and ``fitting`` never import each other:

* :mod:`cubedimer.dataset` - the trajectory data-set format (docs/formats.md): loader, checks, gap filling;
  :mod:`cubedimer.lab_csv` - the CSV dialect labs write (separators, unit labels, rows);
  :mod:`cubedimer.errors` - its one-line :class:`DatasetError`
* :mod:`cubedimer.meta` - the one validated reader of ``meta.json``; :mod:`cubedimer.system` - the system a data
  set records (a levitated dimer, or a generic two-coordinate system declared in meta.json)
* :mod:`cubedimer.noise` - the one white tracking-noise estimate (fourth differences)
* :mod:`cubedimer.terms` - term names and the cubic monomial library over [y, ydot, theta, thetadot]
* :mod:`cubedimer.spectra`, :mod:`cubedimer.poincare`, :mod:`cubedimer.attractors` - signal analysis
  shared by the twin, the fit and the report
* :mod:`cubedimer.consistency`, :mod:`cubedimer.glitches` - cross-run checks of a data set and
  tracking-glitch masking, used by the loader
* :mod:`cubedimer.folds` - the one K-fold split over runs of every held-out score
* :mod:`cubedimer.rk4` - the one compiled fixed-step RK4 kernel (twin and fitted models)
* :mod:`cubedimer.atomic` - atomic file output and the one JSON writer
* :mod:`cubedimer.executor` - the seam for parallel work (local processes or a dask cluster)
* :mod:`cubedimer.cli` - the command-line runner, shared options and one-line errors
* :mod:`cubedimer.config_checks` - the construction-time checks of the frozen configs; :mod:`cubedimer.lazy` - the
  one lazy-import mechanism of the package ``__init__`` modules

* :mod:`cubedimer.compile_cache` - numba's on-disk cache keyed by the suite's sources (set up on import)
* :mod:`cubedimer.distribution` - the installed version (``__version__`` of every package, ``--version``) and the
  check, on import, that no other installation claims one of the suite's top-level names

This package imports none of the three user-facing packages.
"""
from .compile_cache import configure_compile_cache

configure_compile_cache()  # before any compiled function of the suite is defined

from .distribution import __version__, warn_foreign_import_names

warn_foreign_import_names()  # another distribution's `fitting` or `validation` would silently replace the suite's

from .atomic import atomic_save, atomic_write_text, json_safe, save_figure, write_json
from .dataset import Dataset, DatasetError, LoadConfig, Run, load_dataset, load_run
from .executor import ExecutorConfig, map_ordered
from .meta import META_DEFAULTS, META_KEYS, read_meta
from .terms import EQUATION_NAMES, STATE_NAMES, evaluate_library, library_terms, parse_term, term_name

__all__ = [
    "atomic_save", "atomic_write_text", "json_safe", "save_figure", "write_json",
    "Dataset", "DatasetError", "LoadConfig", "Run", "load_dataset", "load_run",
    "ExecutorConfig", "map_ordered",
    "META_DEFAULTS", "META_KEYS", "read_meta",
    "EQUATION_NAMES", "STATE_NAMES", "evaluate_library", "library_terms", "parse_term", "term_name",
]
