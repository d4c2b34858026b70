"""What one frame's measurement holds: the columns of its row (:data:`COLUMNS`) and its status (:data:`STATUS`).

The compiled kernel (:mod:`tracking.measure`) writes one row per frame; the recording's checks
(:mod:`tracking.track`), RUN.json and the overlays read the rows by these names.  The column indices are module
constants (``_I_ALPHA``...) that the compiled functions read as literals.
"""
from __future__ import annotations

__all__ = ["COLUMNS", "NCOL", "STATUS", "STATUS_NAMES", "STATUS_TEXT"]

#: Columns of a frame's measurement row (pixel units unless stated).
COLUMNS = ("status", "v_com", "u_com", "theta", "alpha", "beta", "alpha_free", "beta_free", "edge_rms",
           "edge_width", "area", "tilt", "hinge_gap", "sigma_v", "sigma_theta", "side_a", "side_b", "pixel_noise",
           "u_a", "v_a", "gamma_a", "u_b", "v_b", "gamma_b", "half_side", "n_faces", "background", "squareness_sigma")
# column indices as module constants (the compiled kernel reads them as literals)
_I_ALPHA = COLUMNS.index('alpha')
_I_ALPHA_FREE = COLUMNS.index('alpha_free')
_I_AREA = COLUMNS.index('area')
_I_BACKGROUND = COLUMNS.index('background')
_I_BETA = COLUMNS.index('beta')
_I_BETA_FREE = COLUMNS.index('beta_free')
_I_EDGE_RMS = COLUMNS.index('edge_rms')
_I_EDGE_WIDTH = COLUMNS.index('edge_width')
_I_GAMMA_A = COLUMNS.index('gamma_a')
_I_GAMMA_B = COLUMNS.index('gamma_b')
_I_HALF_SIDE = COLUMNS.index('half_side')
_I_HINGE_GAP = COLUMNS.index('hinge_gap')
_I_N_FACES = COLUMNS.index('n_faces')
_I_PIXEL_NOISE = COLUMNS.index('pixel_noise')
_I_SIDE_A = COLUMNS.index('side_a')
_I_SIDE_B = COLUMNS.index('side_b')
_I_SIGMA_THETA = COLUMNS.index('sigma_theta')
_I_SIGMA_V = COLUMNS.index('sigma_v')
_I_SQUARENESS_SIGMA = COLUMNS.index('squareness_sigma')
_I_THETA = COLUMNS.index('theta')
_I_TILT = COLUMNS.index('tilt')
_I_U_A = COLUMNS.index('u_a')
_I_U_B = COLUMNS.index('u_b')
_I_U_COM = COLUMNS.index('u_com')
_I_V_A = COLUMNS.index('v_a')
_I_V_B = COLUMNS.index('v_b')
_I_V_COM = COLUMNS.index('v_com')
NCOL = len(COLUMNS)
#: Particles a frame's segmentation keeps track of (the largest); a frame with more is not measured.
_MAX_PARTICLES = 8

#: Frame status codes; 0 is a measured frame.
STATUS = {"measured": 0, "corrupt": 1, "no_dimer": 2, "out_of_view": 3, "third_particle": 4, "occlusion": 5,
          "fit_failed": 6, "faces_cross": 7, "motion_blur": 8, "poor_fit": 9,
          "touching": 10}
#: The name of each status code.
STATUS_NAMES = {code: name for name, code in STATUS.items()}
#: What each status means (RUN.json).
STATUS_TEXT = {
    "measured": "measured",
    "corrupt": "blank or corrupt frame (background far from the recording's, or non-finite pixels)",
    "no_dimer": "no particle in view",
    "out_of_view": "the dimer touches the frame's border (partly out of view)",
    "third_particle": "another particle within the dimer's window too close to be masked (its blurred edge within "
                      "reach of the dimer's), or the two cubes apart",
    "occlusion": "the silhouette's area differs from the dimer's (occlusion or a particle touching it)",
    "fit_failed": "too few edge samples on a cube's faces",
    "faces_cross": "fitted faces cross (alpha <= 0 or beta <= 0): no physical bend",
    "motion_blur": "edges wider than the recording's by more than the motion-blur bound",
    "poor_fit": "edges not straight, hinge corners not square or not touching (beyond the bounds)",
    "touching": "the silhouette's centre of mass off the fitted squares' centre (a particle stuck to the dimer)",
}
