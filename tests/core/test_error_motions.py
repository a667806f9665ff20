"""All six error motions per stop from full poses against targets at two depths (SPEC 14), against truth."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.error_motions import error_motions, iso_names
from lps_gui.core.pose_model import _linearize, _retract, solve_poses
from lps_gui.core.rotation import exp_so3
from lps_gui.core.target_model import TargetObservations
from lps_gui.core.target_rig import TargetLayout, observe
from lps_gui.core.targets import Target, pack_targets

CAMERA = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 960.0, 540.0)  # 8 mm, 3.45 um pixels
FAR = Board(10, 7, 30.0, type="charuco", marker_mm=22.0)
NEAR = Board(10, 7, 15.0, type="charuco", marker_mm=11.0)
L = 1524.0


def two_depth_scene(seed: int, two_depth: bool = True, stops: int = 121, noise_px: float = 0.1):
    """The paper's X axis 800 mm from a row of 30 mm targets and, 300 mm nearer, a row of 15 mm targets.

    The camera's attitude follows smooth roll, pitch and yaw of 50-160 urad (plus 3 urad noise); its centre
    bows 10 um across and 15 um along the view. ``two_depth=False`` puts the small targets in the far plane.
    """
    rng = np.random.default_rng(seed)
    far = pack_targets([FAR] * 6)
    near = [Target(f"N{j}", NEAR, 264 + 44 * j) for j in range(10)]
    Q = [np.eye(3)] + [exp_so3(rng.normal(0, 0.01, 3)) for _ in range(15)]
    p = [np.array([340.0 * j, 0, 0]) + (rng.normal(0, 2, 3) if j else 0) for j in range(6)]
    p += [np.array([-20 + 180.0 * j, -52.0 if two_depth else -150.0, -300.0 if two_depth else 0.0])
          + rng.normal(0, 2, 3) for j in range(10)]
    layout = TargetLayout(tuple(far + near), np.stack(Q), np.stack(p))
    x = np.linspace(0, L, stops)
    s = x + rng.normal(0, 0.003, stops)
    theta = np.stack([80e-6 * np.sin(2 * np.pi * x / L), 120e-6 * (x / L) ** 2 + 30e-6 * np.sin(2 * np.pi * x / 400),
                      60e-6 * np.cos(np.pi * x / L)], axis=1) + rng.normal(0, 3e-6, (stops, 3))
    A = np.einsum("kij,jl->kil", exp_so3(theta), exp_so3(np.array([0.01, -0.02, 0.005])).T)  # camera-to-world
    R = np.swapaxes(A, 1, 2)
    bow = np.sin(np.pi * x / L)
    C = np.stack([(5 * 340 + 270 - L) / 2 + s, 44.0 + 10e-3 * bow, -800.0 + 15e-3 * bow], axis=1)
    t = -np.einsum("kij,kj->ki", R, C)
    uv = observe(layout, CAMERA, R, t, noise_px=noise_px, seed=seed)
    obs = TargetObservations(list(layout.targets), uv, x[:, None], [f"v{i:03d}.png" for i in range(stops)])
    return obs, {"theta": theta, "s": s, "C": C, "layout": layout}


def test_iso_names():
    assert list(iso_names("X").values()) == ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX"]
    assert list(iso_names("Y").values()) == ["EYY", "EXY", "EZY", "EAY", "EBY", "ECY"]


def test_the_pose_jacobian_matches_central_differences():
    obs, _ = two_depth_scene(0, stops=6)
    K, T = len(obs.names), len(obs.targets)
    sol = solve_poses(obs, CAMERA, max_iterations=2)
    state = {"R": sol.R, "t": sol.t, "Q": sol.Q, "p": sol.p}
    view, corner = np.nonzero(np.isfinite(obs.corners_px[..., 0]))
    X, tj, uv = obs.own_points[corner], obs.which[corner], obs.corners_px[view, corner]
    lin = _linearize(state, X, tj, view, uv, CAMERA)
    h = 1e-6
    G = 6 * (T - 1)

    def r(dg, dv):
        return _linearize(_retract(state, dg, dv), X, tj, view, uv, CAMERA, False).r

    zero_v = np.zeros((K, 6))
    for c in range(6):
        dv = zero_v.copy()
        dv[:, c] = h
        num = (r(np.zeros(G), dv) - r(np.zeros(G), -dv)) / (2 * h)
        assert np.abs(num - lin.Jv[:, :, c]).max() < 1e-5 * np.abs(lin.Jv[:, :, c]).max()
    for g in range(G):
        e = np.zeros(G)
        e[g] = h
        num = (r(e, zero_v) - r(-e, zero_v)) / (2 * h)
        j, c = divmod(g, 6)
        ana = np.where((tj == j + 1)[:, None], lin.Jt[:, :, c], 0.0)
        assert np.abs(num - ana).max() < 1e-5 * max(np.abs(ana).max(), 1e-12)


def _check(seeds, two_depth=True):
    z2, ratio, resolved, sig = [], [], [], []
    for seed in seeds:
        obs, truth = two_depth_scene(seed, two_depth)
        sol = solve_poses(obs, CAMERA)
        assert sol.converged and sol.used.all()
        em = error_motions(sol, obs.targets_mm, "X")
        true_angles = (truth["theta"] - truth["theta"][em.reference]) @ em.frame * 1e6
        for k, name in enumerate(("roll", "pitch", "yaw")):
            e = em.values[name] - true_angles[:, k]
            e -= e.mean()
            z2.append(np.mean((e / em.centred_sigmas[name]) ** 2))
            ratio.append(np.median(em.centred_sigmas[name]) / np.median(em.single_view_urad[:, k]))
            resolved.append(em.resolved[name])
            sig.append(np.median(em.centred_sigmas[name]))
        e = 1e-3 * em.values["positioning"] - ((truth["s"] - truth["s"][em.reference])
                                                - (obs.targets_mm[:, 0] - obs.targets_mm[em.reference, 0]))
        e -= e.mean()
        z2.append(np.mean((1e3 * e / em.centred_sigmas["positioning"]) ** 2))
    return np.array(z2), np.array(ratio), np.array(resolved), np.array(sig)


@pytest.mark.parametrize("seeds", [range(2), pytest.param(range(10), marks=pytest.mark.slow)])
def test_two_depths_resolve_roll_pitch_and_yaw_at_every_stop(seeds):
    z2, ratio, resolved, sig = _check(seeds)
    assert 0.5 < z2.mean() < 2.0
    assert ratio.max() < 1.3  # each stop's angles within 1.3x of what one view alone resolves (targets known)
    assert np.all(sig < 20.0)  # SPEC 14: about 11, 11, 8 urad from one view
    assert resolved.all()


def test_with_all_targets_in_one_plane_the_roll_is_not_resolved():
    _, _, resolved, sig = _check(range(1), two_depth=False)
    roll, pitch, yaw = resolved
    assert not roll
    assert sig[0] > 30.0 and sig[1] > 30.0  # SPEC 14: 30-60 urad with both rows in one plane
    assert sig[2] < 15.0  # the rotation about the viewing direction stays resolved


def test_the_tool_point_carries_the_abbe_error():
    obs, truth = two_depth_scene(3, stops=41)
    sol = solve_poses(obs, CAMERA)
    offset = np.array([0.0, 100.0, 0.0])  # 100 mm below the camera centre, camera frame
    em = error_motions(sol, obs.targets_mm, "X", tool_cam_mm=offset)
    A = exp_so3(truth["theta"]) @ exp_so3(np.array([0.01, -0.02, 0.005])).T  # camera-to-world, as the scene
    tool = truth["C"] + np.einsum("kij,j->ki", A, offset)
    X = em.frame[:, 0]
    true_tool = 1e3 * ((tool - tool[em.reference]) @ X - (obs.targets_mm[:, 0] - obs.targets_mm[em.reference, 0]))
    e = em.tool_positioning_um - true_tool
    assert np.all(np.abs(e - e.mean()) < 4 * em.tool_positioning_sigma_um.max())
    # the Abbe term is real: the tool and the camera centre differ by about 100 mm x pitch
    assert np.abs(em.tool_positioning_um - em.values["positioning"]).max() > 5.0
