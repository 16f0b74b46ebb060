"""The files of the dataset presets that Python reads back: SyncDreamer's `meta.pkl`, which
`meshtrace batch` writes for `camera_type = "random"`, loaded as SyncDreamer's data loader
loads it (`pickle.load`, with NumPy), without a warning."""

import pickle
import warnings

import numpy as np


def test_syncdreamers_meta_pkl_loads_as_its_script_wrote_it(cli, glb, tmp_path):
    (tmp_path / "m.toml").write_text(
        "[render]\nspp = 1\nwidth = 64\nheight = 64\n\n[[jobs]]\n"
        f'meshes = "{glb}"\npreset = "syncdreamer"\ncamera_type = "random"\nviews = 4\n'
    )
    cli("batch", tmp_path / "m.toml", "--device", "cpu", "-q")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with open(tmp_path / "views" / "materials_joined" / "meta.pkl", "rb") as f:
            K, azimuths, elevations, distances, poses = pickle.load(f)
    # The script's dtypes: K and the azimuths float32, the rest float64.
    assert [a.dtype for a in (K, azimuths, elevations, distances, poses)] == [
        np.float32, np.float32, np.float64, np.float64, np.float64,
    ]
    assert poses.shape == (4, 3, 4) and azimuths.shape == (4,)
    f = 35 * 64 / 32  # the lens over the sensor, in pixels
    assert np.allclose(K, [[f, 0, 32], [0, f, 32], [0, 0, 1]], atol=1e-4)
    assert np.array_equal(azimuths, (np.arange(4) / 4 * np.pi * 2).astype(np.float32))
    assert np.all((np.rad2deg(elevations) >= -10) & (np.rad2deg(elevations) <= 40))
    assert np.all(distances == 1.5)
    # OpenCV's world->camera [R | t]: the centre -R^T t at the view's angles, z forward to
    # the origin.
    R, t = poses[:, :, :3], poses[:, :, 3]
    centres = -np.einsum("nji,nj->ni", R, t)
    a, e = azimuths.astype(np.float64), elevations
    want = distances[:, None] * np.stack([np.cos(a) * np.cos(e), np.sin(a) * np.cos(e), np.sin(e)], -1)
    assert np.allclose(centres, want, atol=1e-6)
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-9)
    assert np.allclose(R[:, 2], -centres / np.linalg.norm(centres, axis=1)[:, None], atol=1e-6)
