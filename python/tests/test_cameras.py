"""Cameras: their matrices and intrinsics project the scene where the renderer draws it,
the two matrix conventions agree, and the layouts follow their formulas."""

import numpy as np
import pytest

import meshtrace as mt

BALL = np.array([0.4, 0.3, -0.2])


def ball_scene():
    return mt.Scene.from_dict(
        {
            "camera": {"position": [0.0, 0.0, 4.0], "look_at": [0.0, 0.0, 0.0]},
            "materials": {"white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
            "objects": [{"sphere": {"center": BALL.tolist(), "radius": 0.05, "subdivisions": 4}, "material": "white"}],
        }
    )


def mask_centre(alpha):
    ys, xs = np.nonzero(alpha > 0.5)
    return np.array([xs.mean() + 0.5, ys.mean() + 0.5])


@pytest.mark.parametrize("view", range(4))
def test_a_point_projects_onto_its_pixels(cpu, view):
    scene = ball_scene()
    camera = mt.cameras.orbit(scene, views=4, elevation=25)[view]
    w, h = 96, 64
    out = cpu.render(scene, camera=camera, spp=16, width=w, height=h, aovs=["alpha"])
    k = camera.intrinsics(w, h)
    to_world = camera.matrix("opencv")
    p = to_world[:3, :3].T @ (BALL - to_world[:3, 3])
    assert p[2] > 0, "in front of an OpenCV camera: +Z"
    pixel = (k @ (p / p[2]))[:2]
    assert np.linalg.norm(pixel - mask_centre(out["alpha"])) < 0.5


def test_the_conventions_differ_by_the_flipped_y_and_z_axes():
    camera = mt.Camera.look_at([1.0, 2.0, 3.0], [0.0, 0.5, 0.0], fov=35.0)
    gl, cv = camera.matrix("opengl"), camera.matrix("opencv")
    assert np.allclose(cv, gl @ np.diag([1.0, -1.0, -1.0, 1.0]))
    assert np.allclose(gl[:3, 2], -np.array(camera.forward))
    for convention, m in (("opengl", gl), ("opencv", cv)):
        again = mt.Camera.from_matrix(m, fov=35.0, convention=convention)
        assert np.allclose(again.matrix(), gl, atol=1e-6)
        assert again.fov == 35.0
    assert np.allclose(mt.Camera.from_matrix(gl[:3]).matrix(), gl, atol=1e-6), "3×4 too"


def test_an_orthographic_camera_keeps_sizes(cpu):
    scene = ball_scene()
    near = mt.Camera.orthographic([0.4, 0.3, 1.0], BALL.tolist(), height=0.2)
    far = mt.Camera.orthographic([0.4, 0.3, 9.0], BALL.tolist(), height=0.2)
    a = cpu.render(scene, camera=near, spp=4, width=40, height=40, aovs=["alpha"])["alpha"]
    b = cpu.render(scene, camera=far, spp=4, width=40, height=40, aovs=["alpha"])["alpha"]
    assert np.array_equal(a > 0.5, b > 0.5)
    # A disc 0.1 across in a view 0.2 high: a quarter of π/4 of the image.
    assert abs((a > 0.5).mean() - np.pi / 16) < 0.02
    assert near.ortho_height == pytest.approx(0.2) and near.matrix()[3, 3] == 1.0
    with pytest.raises(mt.MeshtraceError, match="orthographic"):
        near.intrinsics(40, 40)


def test_an_orbit_goes_around_at_its_elevation(glb):
    scene = mt.load(glb)
    cams = mt.cameras.orbit(scene, views=8, elevation=30)
    assert len(cams) == 8
    for c in cams:
        assert np.degrees(np.arcsin(-c.forward[1])) == pytest.approx(30.0, abs=1e-3)
    azimuths = [np.degrees(np.arctan2(-c.forward[0], -c.forward[2])) for c in cams]
    steps = np.diff(np.unwrap(np.radians(azimuths)))
    assert np.allclose(np.degrees(steps), 45.0, atol=1e-3)


def test_zero123_cameras_stand_on_its_shell(glb):
    scene = mt.load(glb)
    lo, hi = (np.array(b) for b in scene.framed)
    scale, centre = 1.0 / (hi - lo).max(), (lo + hi) / 2
    cams = mt.cameras.preset(scene, "zero123")
    assert len(cams) == 12
    for c in cams:
        # Zero123's sample_spherical: a radius uniform in [1.5, 2.2] about the centre of
        # the object scaled into a unit box, looking at that centre.
        offset = np.array(c.position) - centre
        assert 1.5 - 1e-4 <= np.linalg.norm(offset) * scale <= 2.2 + 1e-4
        assert np.allclose(-offset / np.linalg.norm(offset), c.forward, atol=1e-4)
    # Seeded by object and view: the same object gives the same cameras, another the others.
    assert [c.position for c in mt.cameras.preset(scene, "zero123")] == [c.position for c in cams]
    other = mt.cameras.preset(scene, "zero123", uid="another")
    assert other[0].position != cams[0].position
    assert mt.cameras.preset_settings("zero123") == dict(
        width=512,
        height=512,
        spp=128,
        filter_width=pytest.approx(0.01),
        max_depth=14,
        diffuse_bounces=1,
        glossy_bounces=1,
        transmission_bounces=3,
        transparent=True,
    )
    with pytest.raises(mt.MeshtraceError, match="preset: "):
        mt.cameras.preset(scene, "blender")
    with pytest.raises(mt.MeshtraceError, match="bare mesh"):
        mt.cameras.preset(mt.load("builtin:cornell"), "zero123")


def test_wonder3d_cameras_are_its_orthographic_rig(glb):
    scene = mt.load(glb)
    lo, hi = (np.array(b) for b in scene.framed)
    # Wonder3D's orthographic script scales the box's diagonal, not its largest extent, to 1.
    scale, centre = 1.0 / np.linalg.norm(hi - lo), (lo + hi) / 2
    cams = mt.cameras.preset(scene, "wonder3d")
    assert len(cams) == 13
    for c in cams:
        offset = np.array(c.position) - centre
        assert np.linalg.norm(offset) * scale == pytest.approx(2.0, abs=1e-4)
        assert c.ortho_height * scale == pytest.approx(1.35, abs=1e-5)
    # The rig's front and back cameras face each other; its right one is square to both.
    front, back, right = (np.array(cams[k].forward) for k in range(3))
    assert np.allclose(front, -back, atol=1e-5) and abs(front @ right) < 1e-5
    assert mt.cameras.preset_settings("wonder3d")["transparent"] is False
