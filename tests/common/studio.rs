//! Bare meshes as their files hold them: the studio's ground taken back out of a loaded
//! bare mesh, for tests that look at the file's own triangles.

use meshtrace::scene::Scene;

/// `scene` without the studio ground that a bare mesh gets: its two triangles, its four
/// corners and its material, all appended last. A scene without it is returned as it is.
pub fn without_ground(mut scene: Scene) -> Scene {
    let Some(ground) = scene
        .material_names
        .iter()
        .position(|n| n == "studio ground")
    else {
        return scene;
    };
    assert_eq!(
        ground + 1,
        scene.materials.len(),
        "the ground's material comes last"
    );
    let mesh = &mut scene.mesh;
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| t.material as usize != ground)
        .collect();
    assert_eq!(keep.iter().filter(|k| !**k).count(), 2);
    assert!(!keep[keep.len() - 1] && !keep[keep.len() - 2]);
    mesh.triangles.truncate(keep.len() - 2);
    for corners in [
        &mut mesh.tangent_corners,
        &mut mesh.uv1_corners,
        &mut mesh.color_corners,
    ] {
        if corners.len() == keep.len() {
            corners.truncate(keep.len() - 2);
        }
    }
    if mesh.objects.len() == keep.len() {
        mesh.objects.truncate(keep.len() - 2);
    }
    mesh.positions.truncate(mesh.positions.len() - 4);
    scene.materials.pop();
    scene.material_names.pop();
    scene
}
