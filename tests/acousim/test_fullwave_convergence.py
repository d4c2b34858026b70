"""Mesh convergence of the full-wave hinge stiffness (slow: three mesh levels, six solves)."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("bempp_cl")

from acousim.fullwave.convergence import hinge_quantities  # noqa: E402
from acousim.fullwave.geometry import mesh_family  # noqa: E402

LEVELS = (0.7, 0.5, 0.35)  # 772, 1368, 2132 DOFs


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "open: at g = 0.01 s the stiffness is -9.88, -9.81, -9.12 e-9 N m at q = 0.7, 0.5, 0.35 (not monotone, "
    "last step 7 %); the gap is not resolved by these meshes, see docs/fullwave.md"))
def test_hinge_stiffness_converges():
    """dQ_theta/dtheta at (0, 0) over q = 0.7, 0.5, 0.35 (refinement ratio ~1.4): the corrections shrink
    monotonically, the finest two levels agree within 2 %, and the observed order is at least 1."""
    s = np.array([hinge_quantities(mesh_family(q))["stiffness_nm"] for q in LEVELS])
    assert np.all(s < 0)  # restoring
    d1, d2 = s[1] - s[0], s[2] - s[1]
    assert abs(d2) < abs(d1)
    order = np.log(abs(d1) / abs(d2)) / np.log(1.4)
    assert order >= 1.0, (s, order)
    assert abs(d2 / s[2]) < 0.02
