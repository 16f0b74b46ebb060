//! `meshtrace info --heatmap` and `--bounds`: the heat map counts what the `bvh_cost` AOV
//! counts, ray for ray, colours it by its scale and has a legend; the boxes of a level cover
//! every triangle; bad arguments fail on one line with no file left.

use crate::common;

use common::cli::{assert_fails, output, run};
use common::fs::TempDir;
use common::scenes::cornell;
use meshtrace::bvh::BvhNode;
use meshtrace::figures::{HEATMAP_SAMPLES, level_boxes, ray_costs, viridis};
use meshtrace::film::Aov;
use meshtrace::math::Aabb;
use meshtrace::render::RenderJob;

/// The heat map's costs are the bvh_cost AOV of a render with as many samples, exactly.
#[test]
fn heatmap_costs_are_the_bvh_cost_aov() {
    let (rs, mut s) = cornell();
    (s.width, s.height, s.spp) = (40, 30, HEATMAP_SAMPLES);
    let costs = ray_costs(&rs, &s);
    let job = RenderJob::new(s).with_aovs(Aov::BvhCost.bit(), false);
    let film = common::cpu_render(&rs, &job);
    let Some(values) = film.aov_values(Aov::BvhCost) else {
        panic!("no bvh_cost AOV")
    };
    let meshtrace::film::AovValues::F32(aov) = &values[0] else {
        panic!("bvh_cost is not f32")
    };
    assert_eq!(&costs, aov);
    let mean = costs.iter().sum::<f32>() / costs.len() as f32;
    assert!(mean > 3.0, "mean cost {mean}: the rays should visit nodes");
}

#[test]
fn heatmap_png_has_the_colours_of_its_scale_and_a_legend() {
    let dir = TempDir::new("heatmap");
    let (code, out) = run(&dir, &["info", "builtin:cornell", "--heatmap", "heat.png"]);
    assert_eq!(code, 0, "{out}");
    let img = image::open(dir.path().join("heat.png"))
        .unwrap()
        .into_rgb8();
    let (rs, s) = cornell();
    // The image at the scene's size, then the legend 150 pixels wide.
    assert_eq!(
        (img.width(), img.height()),
        (s.width + 150, s.height.max(200))
    );
    let costs = ray_costs(&rs, &s);
    let top = costs.iter().copied().fold(1.0f32, f32::max);
    for (i, &c) in costs.iter().enumerate().step_by(97) {
        let (x, y) = (i as u32 % s.width, i as u32 / s.width);
        assert_eq!(
            img.get_pixel(x, y).0,
            viridis(c / top),
            "pixel ({x}, {y}), cost {c}"
        );
    }
    // The legend: a colour bar from the darkest to the brightest colour, and text.
    let bar_x = s.width + 20;
    assert_eq!(img.get_pixel(bar_x, 46).0, viridis(1.0));
    assert_eq!(img.get_pixel(bar_x, img.height() - 17).0, viridis(0.0));
    let dark_text = (s.width..img.width())
        .flat_map(|x| (0..40).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&v| v < 80))
        .count();
    assert!(
        dark_text > 100,
        "no title text in the legend ({dark_text} dark pixels)"
    );
}

/// The triangles under node `i`.
fn triangles_under(nodes: &[BvhNode], i: usize) -> usize {
    let n = nodes[i];
    if n.is_leaf() {
        n.count as usize
    } else {
        triangles_under(nodes, i + 1) + triangles_under(nodes, n.left_or_first as usize)
    }
}

/// The boxes of any level split the triangles between them (each under exactly one box),
/// cover them, and number at most 2^level.
#[test]
fn the_boxes_of_a_level_cover_every_triangle_once() {
    let (rs, _) = cornell();
    let nodes = &rs.bvh.nodes;
    for depth in 0..8 {
        let boxes = level_boxes(nodes, depth);
        assert!(
            boxes.len() <= 1 << depth,
            "level {depth}: {} boxes",
            boxes.len()
        );
        let under: usize = boxes
            .iter()
            .map(|b| {
                let i = nodes
                    .iter()
                    .position(|n| n == b)
                    .expect("a node of the tree");
                triangles_under(nodes, i)
            })
            .sum();
        assert_eq!(under, rs.tris.len(), "level {depth}");
        for t in &rs.tris {
            let tri = Aabb::from_points(&t.corners());
            assert!(
                boxes.iter().any(|b| {
                    let b = b.bounds();
                    b.min.cmple(tri.min).all() && tri.max.cmple(b.max).all()
                }),
                "level {depth}: a triangle outside every box"
            );
        }
    }
}

#[test]
fn bounds_png_draws_a_level_over_a_render() {
    let dir = TempDir::new("bounds");
    let result = output(
        &dir,
        &["info", "builtin:cornell", "--bounds", "2", "boxes.png"],
    );
    let out = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let (rs, s) = cornell();
    let n = level_boxes(&rs.bvh.nodes, 2).len();
    assert!(
        out.contains(&format!("boxes.png (level 2: {n} boxes)")),
        "{out}"
    );
    let img = image::open(dir.path().join("boxes.png"))
        .unwrap()
        .into_rgb8();
    assert_eq!((img.width(), img.height()), (s.width, s.height));
    // Saturated box edges over a dimmed, grey-walled render.
    let vivid = img
        .pixels()
        .filter(|p| {
            let (mx, mn) = (p.0.iter().max().unwrap(), p.0.iter().min().unwrap());
            *mx > 150 && mx - mn > 100
        })
        .count();
    assert!(vivid > 200, "only {vivid} vivid pixels: no boxes drawn");
}

#[test]
fn bad_figure_arguments_fail_cleanly() {
    let dir = TempDir::new("figures-bad");
    assert_fails(
        &dir,
        &["info", "builtin:cornell", "--bounds", "x", "b.png"],
        &["--bounds", "`x` is not a tree level"],
    );
    assert_fails(
        &dir,
        &["info", "builtin:cornell", "--heatmap", "h.jpg"],
        &["h.jpg", "PNG"],
    );
    assert_fails(
        &dir,
        &["info", "builtin:cornell", "--heatmap", "no/such/dir/h.png"],
        &["h.png"],
    );
}
