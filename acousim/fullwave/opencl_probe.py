"""Whether bempp-cl's OpenCL backend really works here: a trial assembly in a child process, cached per environment.

An OpenCL driver that is installed is not yet one that works.  pyopencl may find a CPU device while the driver
cannot build bempp-cl's kernels; some drivers then raise (``clCreateKernel failed: INVALID_KERNEL_NAME``), others
abort the whole process from inside their compiler (LLVM's "Cannot select" on a vector intrinsic), which no
``try`` can catch.  So under ``CUBEDIMER_BEM_DEVICE=auto`` the solver takes OpenCL only after this probe has run
the solver's own Burton-Miller assembly and solve of a coarse dimer (every kernel a solve uses: the double-layer
and hypersingular operators, regular and singular quadrature, the mirror-reduced test space) on the OpenCL device
**in a child process**, and found a finite field.  A probe that fails, aborts or times out means "no OpenCL",
with one log line.  (That both backends give the same field is a test of the suite's, run where this probe
succeeds.)

The verdict is cached in the suite's user cache (``<cache>/opencl/verdict-<key>.json``) under a key of the
versions of pyopencl, pocl, bempp-cl and numpy, the Python version and the processor, so that the probe (about
half a minute) runs once per environment, not once per command; a cached verdict that cannot be read is
probed again.  Processes that need the verdict at once (the parallel workers of a build) wait for the first one's
probe (:func:`cubedimer.cache_lock.cache_entry_lock`) instead of each running their own.  A trial assembly that
runs out of time, or cannot start, says nothing about the driver (a loaded machine is slow, not broken): the
command assembles on numba, and that verdict holds for :data:`RETRY_AFTER_S` only (so that the other workers of the
same command do not each wait out the timeout again), after which a command probes again.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import platform
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from cubedimer.atomic import write_json
from cubedimer.cache_lock import cache_entry_lock
from cubedimer.compile_cache import suite_cache_root

__all__ = ["OpenCLVerdict", "TrialAssembly", "opencl_verdict", "run_probe", "environment_key", "PROBE_TIMEOUT_S",
           "RETRY_AFTER_S"]

log = logging.getLogger(__name__)

#: Seconds the child process may take (compiling the OpenCL kernels takes 10-30 s on one core).
PROBE_TIMEOUT_S = 600.0

#: Seconds an inconclusive verdict (a trial that ran out of time or could not start) is kept before probing again.
RETRY_AFTER_S = 3600.0

#: Packages whose versions key the cached verdict.
KEY_PACKAGES = ("pyopencl", "pocl-binary-distribution", "bempp-cl", "numpy", "numba")

#: What the child runs: the solver's assembly and solve of the coarsest dimer mesh on the OpenCL backend.
PROBE_CODE = textwrap.dedent("""
    import os, sys
    import numpy as np
    from acousim.fullwave.geometry import dimer_bodies, mesh_family
    from acousim.fullwave.solver import BEM_DEVICE_ENV, solve_scattering
    os.environ[BEM_DEVICE_ENV] = "opencl"
    sol = solve_scattering(dimer_bodies(0.3, mesh_family(2.0)))
    if sol.timings["device"] != "opencl":
        sys.exit(f"assembled on {sol.timings['device']}, not opencl")
    field = np.concatenate([sol.p_cos, sol.p_sin])
    if not (np.all(np.isfinite(field)) and np.max(np.abs(field)) > 0):
        sys.exit("the OpenCL assembly gave a field that is not finite, or zero")
    print("opencl-probe-ok", sol.n_dofs)
""")


@dataclass(frozen=True)
class OpenCLVerdict:
    """Whether the OpenCL backend works in this environment.

    Attributes
    ----------
    works : bool
        True when the trial assembly ran on OpenCL and gave a finite field.
    reason : str
        One line: why not, or what ran.
    key : str
        The environment key the verdict is cached under (:func:`environment_key`).
    """

    works: bool
    reason: str
    key: str


@dataclass(frozen=True)
class TrialAssembly:
    """How the trial assembly in the child process went.

    Attributes
    ----------
    works : bool
        True when it ran on OpenCL and gave a finite field.
    reason : str
        One line: what ran, or how it failed (exit status or signal, and the child's last error line).
    conclusive : bool
        False when it ran out of time or could not start: that is the machine's state, not the driver's, and is
        kept for :data:`RETRY_AFTER_S` only.
    """

    works: bool
    reason: str
    conclusive: bool = True


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "-"


def _processor() -> str:
    """The processor's model and instruction-set flags (a driver's compiler targets them)."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or platform.machine()
    wanted = [line for line in text.splitlines() if line.startswith(("model name", "flags"))]
    return "\n".join(sorted(set(wanted))) or platform.machine()


def environment_key() -> str:
    """16 hex digits naming this environment: the versions of :data:`KEY_PACKAGES`, Python and the processor."""
    parts = [f"{p}={_version(p)}" for p in KEY_PACKAGES] + [sys.version, platform.machine(), _processor()]
    return hashlib.sha1("\n".join(parts).encode()).hexdigest()[:16]


def _cache_file(key: str) -> Path:
    return suite_cache_root() / "opencl" / f"verdict-{key}.json"


def _read_cached(path: Path) -> OpenCLVerdict | None:
    """The cached verdict; None when absent, unreadable, or inconclusive and older than :data:`RETRY_AFTER_S`."""
    try:
        d = json.loads(path.read_text())
        if not d.get("conclusive", True) and not time.time() - float(d["written"]) < RETRY_AFTER_S:
            return None
        return OpenCLVerdict(works=bool(d["works"]), reason=str(d["reason"]), key=str(d["key"]))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None  # absent or unreadable: probe again


def run_probe(code: str = PROBE_CODE, timeout_s: float = PROBE_TIMEOUT_S) -> TrialAssembly:
    """Run ``code`` in a child Python; it works when the child's last line starts with ``opencl-probe-ok``."""
    env = dict(os.environ, POCL_MAX_PTHREAD_COUNT=os.environ.get("POCL_MAX_PTHREAD_COUNT", "1"))
    try:
        res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                             timeout=timeout_s, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return TrialAssembly(False, f"the trial assembly did not finish in {timeout_s:.0f} s", conclusive=False)
    except OSError as exc:
        return TrialAssembly(False, f"the trial assembly could not start ({exc})", conclusive=False)
    out = res.stdout.strip().splitlines()
    if res.returncode == 0 and out and out[-1].startswith("opencl-probe-ok"):
        return TrialAssembly(True, f"trial assembly of {out[-1].split()[-1]} DOFs ran on OpenCL")
    lines = [ln.strip() for ln in res.stderr.strip().splitlines() if ln.strip()]
    status = f"killed by signal {-res.returncode}" if res.returncode < 0 else f"exit status {res.returncode}"
    return TrialAssembly(False, f"the trial assembly failed ({status}): {lines[-1][:300] if lines else 'no message'}")


def _opencl_device_found() -> bool:
    """Whether pyopencl is installed and lists a CPU device (cheap; decides whether a probe is worth running)."""
    try:
        import pyopencl as cl

        return any(p.get_devices(device_type=cl.device_type.CPU) for p in cl.get_platforms())
    except Exception:  # not installed, no platform (ICD) or no driver
        return False


def opencl_verdict(refresh: bool = False) -> OpenCLVerdict:
    """Whether bempp-cl's OpenCL backend works here (module docstring); cached per environment.

    Parameters
    ----------
    refresh : bool
        Probe again even when a verdict is cached.
    """
    key = environment_key()
    if not _opencl_device_found():
        return OpenCLVerdict(False, "pyopencl finds no OpenCL CPU device", key)
    path = _cache_file(key)
    with cache_entry_lock(path, "the OpenCL verdict"):  # a process that waited finds the first one's verdict
        cached = None if refresh else _read_cached(path)
        if cached is not None and cached.key == key:
            return cached
        log.info("probing bempp-cl's OpenCL backend once for this environment (a trial assembly in a child process)")
        trial = run_probe()
        if not trial.works:
            again = f" (probed again after {RETRY_AFTER_S / 60:.0f} min: a loaded machine is not a broken driver)"
            log.warning("OpenCL backend not used: %s; assembling on numba%s", trial.reason,
                        "" if trial.conclusive else again)
        record = {"works": trial.works, "reason": trial.reason, "key": key}
        if not trial.conclusive:
            record.update(conclusive=False, written=time.time())
        try:
            write_json(path, record)
        except OSError as exc:  # an unwritable cache only costs a probe next time
            log.debug("could not cache the OpenCL verdict: %s", exc)
    return OpenCLVerdict(trial.works, trial.reason, key)
