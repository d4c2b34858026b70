"""The rocking and sideways modes of the dimer: stiffness by boundary-element solves, Floquet multipliers along the
held-y orbits (docs/twin.md, "Rocking and sideways").

    python docs/scripts/rocking_stability.py CACHE            # solves the missing poses (resumable), then both tables
    python docs/scripts/rocking_stability.py CACHE --no-solve # the tables from the poses already in CACHE

Every pose (dimer, mesh, theta, psi, x) is one solve (22-44 s on the standard mesh, 7.5 min on the default table's
mesh, one core), cached as one JSON file in CACHE: the total force and torque about the centre of mass, (A, B, C) at
3 kPa, by the momentum flux through a sphere and by the surface tractions (acousim.fullwave.antisymmetric_loads).  Then, for each
dimer, the stiffness over the bend (K_psipsi, K_xpsi at theta = 0-0.8, mirrored to negative bends) and, along the
locked held-y orbits of its cells (acousim.atlas.held_y), the rocking pair's Floquet multipliers
(acousim.atlas.rocking_stability).
"""
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

from cubedimer.atomic import write_json

P_SOLVE = 3000.0
STEP = 0.02
THETAS = (0.0, 0.2, 0.4, 0.6, 0.8)
# (label, side, g/s): the default dimer and the dimers of the held-y orbits of docs/twin.md
DIMERS = {"s500_g0.01": (500e-6, 0.01), "s500_g0.02": (500e-6, 0.02), "s700_g0.05": (700e-6, 0.05)}
# (dimer, mesh, theta, psi, x): the sweep on the standard mesh, the linearity and mesh checks on the default dimer
POSES = ([(d, "standard", th, STEP, 0.0) for d in DIMERS for th in THETAS]
         + [("s500_g0.01", "standard", th, 2 * STEP, 0.0) for th in (0.2, 0.6)]
         + [("s500_g0.01", "coarse", 0.2, STEP, 0.0), ("s500_g0.01", "coarse", 0.2, STEP, 50e-6),
            ("s500_g0.01", "table", 0.2, STEP, 0.0)])
# (dimer, p0, A, orbit classes): the held-y cells whose locked orbits are checked
# the rocking stiffness times these factors: how far each orbit is from a parametric resonance of the rocking mode
K_SCALES = (0.7, 0.8, 0.9, 1.1, 1.2, 1.3)
CELLS = [("s500_g0.01", 3000.0, 100e-6), ("s500_g0.01", 3000.0, 200e-6), ("s500_g0.01", 3000.0, 300e-6),
         ("s500_g0.02", 3000.0, 50e-6), ("s500_g0.02", 3000.0, 100e-6),
         ("s700_g0.05", 6000.0, 300e-6), ("s700_g0.05", 6000.0, 500e-6), ("s700_g0.05", 4500.0, 300e-6),
         ("s500_g0.01", 6000.0, 200e-6), ("s500_g0.02", 4500.0, 100e-6)]


def mesh_spec(dimer: str, mesh: str):
    from acousim.fullwave.geometry import mesh_family
    from acousim.fullwave.mesh_rules import edge_graded_mesh_spec

    side, gs = DIMERS[dimer]
    if mesh == "table":
        return edge_graded_mesh_spec(side, gs * side)
    return mesh_family({"standard": 0.5, "coarse": 1.0}[mesh], side=side, gap=gs * side)


def pose_path(cache: Path, pose) -> Path:
    d, mesh, th, psi, x = pose
    return cache / f"{d}_{mesh}_th{th:+.3f}_psi{psi:.3f}_x{x * 1e6:.0f}um.json"


def solve_pose(cache: Path, pose) -> None:
    from acousim.fullwave.antisymmetric_loads import rocked_dimer_bodies, total_loads
    from acousim.fullwave.solver import solve_scattering

    d, mesh, th, psi, x = pose
    t0 = time.perf_counter()
    spec = mesh_spec(d, mesh)
    sol = solve_scattering(rocked_dimer_bodies(th, psi, x, spec))
    centre = np.array([x, 0.0, 0.0])
    out = {"dimer": d, "mesh": mesh, "spec": spec.settings(), "theta": th, "psi": psi, "x_m": x, "dofs": sol.n_dofs,
           "pressure_pa": P_SOLVE, "two_k": 2 * sol.medium.wavenumber, "symmetry": sol.timings["symmetry"]}
    for method in ("flux", "surface"):
        f, t = total_loads(sol, P_SOLVE, centre, method)
        out[method] = {"force": f.tolist(), "torque": t.tolist()}
    f32, t32 = total_loads(sol, P_SOLVE, centre, "flux", n_polar=32)
    out["flux32"] = {"force": f32.tolist(), "torque": t32.tolist()}
    out["seconds"] = time.perf_counter() - t0
    write_json(pose_path(cache, pose), out)
    print(f"solved {pose_path(cache, pose).name}: {sol.n_dofs} DOFs, {out['seconds']:.0f} s", flush=True)


def load(cache: Path, pose) -> dict | None:
    p = pose_path(cache, pose)
    return json.loads(p.read_text()) if p.exists() else None


def stiffness_table(cache: Path, dimer: str, mesh: str = "standard"):
    from acousim.fullwave.antisymmetric_loads import RockingStiffness, pose_stiffness

    rows = [load(cache, (dimer, mesh, th, STEP, 0.0)) for th in THETAS]
    ks = [pose_stiffness(r["flux"]["force"], r["flux"]["torque"], STEP) for r in rows]
    return RockingStiffness(np.array(THETAS), np.array([k["k_psipsi"] for k in ks]), np.array([k["k_xpsi"] for k in ks]),
                            two_k=rows[0]["two_k"], pressure_amplitude_pa=P_SOLVE), ks


def print_stiffness(cache: Path) -> None:
    from acousim.atlas.field_drops import atlas_dynamics
    from acousim.atlas.rocking_stability import AntisymmetricInertia
    from acousim.fullwave.antisymmetric_loads import pose_stiffness

    for dimer, (side, gs) in DIMERS.items():
        table, ks = stiffness_table(cache, dimer)
        sur = atlas_dynamics(side, gs, P_SOLVE, 45_650.0).force_model
        inert = AntisymmetricInertia.from_hinge_inertia(sur.mass, sur.inertia_const, sur.inertia_sin2)
        f_y = sur.linear_frequencies()[0]
        z = sur.z_eq + sur.equilibrium()[1]
        print(f"\n{dimer} at {P_SOLVE:g} Pa, Z_eq {z * 1e6:.1f} um, f_y {f_y:.2f} Hz, M {sur.mass:.4g} kg")
        print("theta | K_psipsi(Z_eq) [N m/rad] | K_xpsi(Z_eq) [N/rad] | point-cube -X^2 dF_Z/dZ | ratio | "
              "f_psi [Hz] | f_psi/f_y | K_xpsi/(K_psipsi/X) | F_Z flux/table - 1 | F_Z surface/flux - 1")
        c, s = np.cos(table.two_k * z), np.sin(table.two_k * z)
        for th, k in zip(THETAS, ks):
            r = load(cache, (dimer, "standard", th, STEP, 0.0))
            kpp = k["k_psipsi"] @ [1, c, s]
            kxp = k["k_xpsi"] @ [1, c, s]
            fz = np.array(k["fz"])
            dfz = table.two_k * (-fz[1] * s + fz[2] * c)
            x_c = inert.arm * np.cos(np.pi * th / 4)
            point = -x_c**2 * dfz
            f_psi = np.sqrt(max(kpp, 0.0) / float(inert.rocking_inertia(th))) / (2 * np.pi)
            fz_tab = float(sur.force_z(th, z - sur.z_eq))
            fz_sur = np.array(r["surface"]["force"])[:, 2] @ [1, c, s]
            print(f"{th:.1f} | {kpp:.4e} | {kxp:+.3e} | {point:.4e} | {kpp / point:.4f} | {f_psi:.2f} | "
                  f"{f_psi / f_y:.4f} | {kxp / (kpp / x_c):+.2e} | {fz @ [1, c, s] / fz_tab - 1:+.2e} | "
                  f"{fz_sur / (fz @ [1, c, s]) - 1:+.2e}")
    base = load(cache, ("s500_g0.01", "standard", 0.2, STEP, 0.0))
    z = atlas_dynamics(500e-6, 0.01, P_SOLVE, 45_650.0).force_model.z_eq
    tk = base["two_k"]
    at = lambda r, step, key="flux": pose_stiffness(r[key]["force"], r[key]["torque"], step)["k_psipsi"] @ [
        1, np.cos(tk * z), np.sin(tk * z)]
    print("\nchecks on s500_g0.01 at theta 0.2, K_psipsi(Z_eq):")
    for mesh in ("coarse", "standard", "table"):
        r = load(cache, ("s500_g0.01", mesh, 0.2, STEP, 0.0))
        if r:
            print(f"  {mesh} mesh ({r['dofs']} DOFs): {at(r, STEP):.5e} (surface tractions {at(r, STEP, 'surface'):.5e},"
                  f" sphere 32 points {at(r, STEP, 'flux32'):.5e})")
    for th in (0.2, 0.6):
        r1, r2 = load(cache, ("s500_g0.01", "standard", th, STEP, 0.0)), load(cache, ("s500_g0.01", "standard", th, 2 * STEP, 0.0))
        if r1 and r2:
            print(f"  linearity at theta {th}: K(2 step) / K(step) - 1 = {at(r2, 2 * STEP) / at(r1, STEP) - 1:+.2e}")
    r0, rx = load(cache, ("s500_g0.01", "coarse", 0.2, STEP, 0.0)), load(cache, ("s500_g0.01", "coarse", 0.2, STEP, 50e-6))
    if r0 and rx:
        d = np.max(np.abs(np.array(rx["flux"]["force"]) - np.array(r0["flux"]["force"]))) / np.max(np.abs(r0["flux"]["force"]))
        dt = np.max(np.abs(np.array(rx["flux"]["torque"]) - np.array(r0["flux"]["torque"]))) / np.max(np.abs(r0["flux"]["torque"]))
        print(f"  translated by 50 um: force changes by {d:.1e}, torque by {dt:.1e} of their largest coefficient")


def print_floquet(cache: Path) -> None:
    from acousim.atlas.field_drops import atlas_dynamics, settled_outcome
    from acousim.atlas.held_y import HeldYConfig, held_y_orbits
    from acousim.atlas.rocking_stability import (AntisymmetricInertia, rocking_arguments, rocking_damping_rate,
                                                 rocking_multipliers, sample_orbit)
    from acousim.atlas.field_drops import AtlasDimer

    print("\ncell | class | lock | hinge amplitude | theta range | max |mu| rocking pair, undamped | arg(mu)/2pi | "
          "f_psi T_y range | gamma_psi [1/s] | max |mu| with gamma_psi | undamped max |mu| with K_psipsi x "
          + ", ".join(f"{k:g}" for k in K_SCALES))
    for dimer, p0, amp in CELLS:
        side, gs = DIMERS[dimer]
        table, _ = stiffness_table(cache, dimer)
        poly = table.polynomials()
        dyn = atlas_dynamics(side, gs, p0, 45_650.0)
        sur = dyn.force_model
        inert = AntisymmetricInertia.from_hinge_inertia(sur.mass, sur.inertia_const, sur.inertia_sin2)
        cfg = HeldYConfig(dimers=(AtlasDimer(side, gs),), pressures_pa=(p0,), amplitudes_m=(amp,))
        n_per = cfg.samples_per_period
        periods = cfg.settle_periods + cfg.analysed_periods
        t, out, n_valid, status, period, args, _ = held_y_orbits(dyn, amp, cfg.starts(), periods, n_per)
        keep = 2 * cfg.analysed_periods * n_per
        seen = {}
        for k in range(len(out)):
            if status[k]:
                continue
            res = settled_outcome(t[-keep:], out[k, -keep:])
            if not (res["outcome"].startswith("locked-") and res["long_lived"]):
                continue
            p = int(res["lock_ratio"].split(":")[0]) if res["lock_ratio"] else 1
            x_end = out[k, -1]
            closure = np.max(np.abs(x_end[2:] - out[k, -1 - p * n_per, 2:]) / [1.0, 2 * np.pi / period])
            if closure > 1e-3:
                continue
            orbit = sample_orbit(args, x_end, p * period, 256)
            if orbit[:, 2].max() > table.theta_max or orbit[:, 2].min() < -table.theta_max:
                continue
            rargs = rocking_arguments(orbit[:-1], p * period, poly, table.two_k, sur.z_eq, inert,
                                      load_scale=(p0 / P_SOLVE) ** 2)
            mu = rocking_multipliers(rargs, p * period)
            kpp, _ = table.at(orbit[:, 2], sur.z_eq + orbit[:, 0], p0)
            f_psi = np.sqrt(np.maximum(kpp, 0) / inert.rocking_inertia(orbit[:, 2])) / (2 * np.pi) * period
            gamma = rocking_damping_rate(inert, float(np.mean(orbit[:, 2])), float(np.mean(f_psi)) / period)
            mu_d = rocking_multipliers(rocking_arguments(orbit[:-1], p * period, poly, table.two_k, sur.z_eq, inert,
                                                         load_scale=(p0 / P_SOLVE) ** 2, gamma_psi=gamma), p * period)
            scaled = []
            for ks in K_SCALES:
                sp = {"k_psipsi": ks * poly["k_psipsi"], "k_xpsi": poly["k_xpsi"]}
                scaled.append(np.abs(rocking_multipliers(rocking_arguments(
                    orbit[:-1], p * period, sp, table.two_k, sur.z_eq, inert, load_scale=(p0 / P_SOLVE) ** 2),
                    p * period)).max())
            key = (res["outcome"], res["lock_ratio"], round(res["amp_theta"], 2))
            if key in seen:
                continue
            seen[key] = True
            print(f"{dimer}, {p0 / 1e3:g} kPa, A {amp * 1e6:.0f} um | {res['outcome']} | {res['lock_ratio'] or '1:1'} | "
                  f"{res['amp_theta']:.3f} | {orbit[:, 2].min():+.2f}..{orbit[:, 2].max():+.2f} | "
                  f"{np.abs(mu).max():.6f} | {np.abs(np.angle(mu)).max() / (2 * np.pi):.4f} | "
                  f"{f_psi.min():.3f}-{f_psi.max():.3f} | {gamma:.3f} | {np.abs(mu_d).max():.6f} | "
                  + ", ".join(f"{v:.4f}" for v in scaled), flush=True)


def main() -> None:
    logging.basicConfig(level=logging.WARNING)
    cache = Path(sys.argv[1])
    cache.mkdir(parents=True, exist_ok=True)
    if "--no-solve" not in sys.argv:
        for pose in POSES:
            if not pose_path(cache, pose).exists():
                solve_pose(cache, pose)
    print_stiffness(cache)
    print_floquet(cache)


if __name__ == "__main__":
    main()
