"""The light-field scene renderer: geometry against the pinhole law, through the board renderer's optics."""
import numpy as np
import pytest

from lps_gui.camera.render_scene import SceneRenderer
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.truth.scene import Scene, ScenePlane, scene_for_rig, scene_points, visible_points
from lps_gui.core.truth.simulate import small_spec


def _one_plane(depth_mm: float) -> Scene:
    plane = ScenePlane("wall", np.array([0.0, 0.0, depth_mm]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]),
                       (2000.0, 2000.0), texture_seed=3, texel_mm=0.6 * depth_mm / 400.0, depth_mm=depth_mm)
    return Scene((plane,))


def test_a_camera_moved_along_x_or_y_shifts_a_fronto_parallel_plane_by_f_d_over_z():
    intr = CameraIntrinsics.from_values((320, 240), 400.0, 400.0, 160.0, 120.0)
    r = SceneRenderer(_one_plane(500.0), intr)
    R = np.eye(3)
    a = r.render_float(R, np.zeros(3))
    right = r.render_float(R, np.array([-5.0, 0.0, 0.0]))  # centre at x = +5 mm: the scene moves 4 px left
    down = r.render_float(R, np.array([0.0, -2.5, 0.0]))  # y = +2.5 mm: 2 px up
    assert np.abs(right[:, :-4] - a[:, 4:])[10:-10, 10:-10].max() < 0.01
    assert np.abs(down[:-2, :] - a[2:, :])[10:-10, 10:-10].max() < 0.01
    assert np.abs(right - a).max() > 10.0  # the texture has contrast: the comparison above can fail


def test_the_standard_scene_has_parallel_planes_at_their_depths_and_points_on_them():
    spec = small_spec()
    scene = scene_for_rig(spec.rig, spec.plan.targets())
    names = [p.name for p in scene.planes]
    assert names[-2:] == ["slanted", "backdrop"]
    u = spec.rig.u_board
    C0 = spec.rig.C0_board
    for p in scene.planes:
        if p.depth_mm is not None:  # parallel to the motion: same depth from every camera on the line
            assert abs(p.normal @ u) < 1e-12
            assert (p.origin - C0) @ p.normal == pytest.approx(p.depth_mm, rel=1e-9)
    P, owner = scene_points(scene)
    assert len(P) == 4 * 45
    assert visible_points(scene, C0, P, owner).mean() > 0.9
    assert Scene.from_dict(scene.to_dict()).to_dict() == scene.to_dict()


def test_scene_images_carry_the_board_renderers_noise_and_blur():
    spec = small_spec()
    scene = scene_for_rig(spec.rig, spec.plan.targets())
    intr = spec.rig.intrinsics
    quiet = SceneRenderer(scene, intr, noise_grey=0.0)
    noisy = SceneRenderer(scene, intr, noise_grey=3.0, rays=quiet.rays)
    R = spec.rig.R_cam_board
    t = -R @ spec.rig.C0_board
    clean = quiet.render(R, t).astype(float)
    grainy = noisy.render(R, t, np.random.default_rng(1)).astype(float)
    assert clean.shape == (intr.image_size[1], intr.image_size[0])
    assert np.std(grainy - clean) == pytest.approx(3.0, rel=0.1)
