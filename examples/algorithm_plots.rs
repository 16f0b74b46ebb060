//! Draws the plots of `docs/algorithms.md` from the results of
//! `cargo bench --bench algorithms`: criterion's estimates (`target/criterion/`) and the
//! bench's own measures (`target/algorithms/results.json`), into `docs/algorithms/*.png`,
//! and prints the doc's tables of the same numbers (Markdown) on stdout.
//!
//! ```sh
//! cargo bench --bench algorithms
//! cargo run --release --example algorithm_plots
//! ```
//!
//! Drawn as `meshtrace info --heatmap` draws (`src/figures.rs`): plotters into an RGB
//! buffer, text in the bundled DejaVu Sans subset (ASCII only), the PNG encoded by `image`.

use anyhow::{Context, Result, anyhow, bail};
use meshtrace::figures::viridis;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The font of every plot's text.
const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-subset.ttf");

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Where the inputs are: criterion's folder and the bench's, in the target folder (as
/// criterion finds it: `$CARGO_TARGET_DIR`, else `target/`).
struct Inputs {
    criterion: PathBuf,
    measures: Value,
}

impl Inputs {
    fn load() -> Result<Self> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let target = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join("target"));
        let path = target.join("algorithms/results.json");
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "{}: run `cargo bench --bench algorithms` first",
                path.display()
            )
        })?;
        Ok(Self {
            criterion: target.join("criterion"),
            measures: serde_json::from_str(&text)
                .with_context(|| format!("{}: not JSON", path.display()))?,
        })
    }

    /// A bench's median time per iteration (s) and elements per iteration.
    fn timing(&self, group: &str, name: &str) -> Result<(f64, f64)> {
        let dir = self.criterion.join(group).join(name).join("new");
        let read = |file: &str| -> Result<Value> {
            let path = dir.join(file);
            let text = std::fs::read_to_string(&path).with_context(|| {
                format!(
                    "{}: run `cargo bench --bench algorithms` (unfiltered) first",
                    path.display()
                )
            })?;
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))
        };
        let ns = read("estimates.json")?["median"]["point_estimate"]
            .as_f64()
            .ok_or_else(|| anyhow!("{group}/{name}: no median estimate"))?;
        let elements = read("benchmark.json")?["throughput"]["Elements"]
            .as_f64()
            .ok_or_else(|| anyhow!("{group}/{name}: no element count"))?;
        Ok((ns * 1e-9, elements))
    }

    /// Nanoseconds per element of a bench.
    fn ns_per(&self, group: &str, name: &str) -> Result<f64> {
        let (s, n) = self.timing(group, name)?;
        Ok(s / n * 1e9)
    }

    /// Millions of elements per second of a bench.
    fn mrate(&self, group: &str, name: &str) -> Result<f64> {
        let (s, n) = self.timing(group, name)?;
        Ok(n / s * 1e-6)
    }

    fn measure(&self, key: &str) -> Result<&Value> {
        match &self.measures[key] {
            Value::Null => bail!("results.json has no {key}"),
            v => Ok(v),
        }
    }
}

/// The paired ratios of `names` in group `path` of the bench's `paired` measure: median
/// and quartiles of each one's time over the reference's.
fn paired_ratios(inputs: &Inputs, path: &[&str], names: &[&str]) -> Result<Vec<(f64, f64, f64)>> {
    let mut g = inputs.measure("paired")?;
    for p in path {
        g = &g[*p];
    }
    names
        .iter()
        .map(|n| {
            let r = &g["ratios"][*n];
            Ok((
                num(&r["median"], "paired median")?,
                num(&r["q1"], "paired q1")?,
                num(&r["q3"], "paired q3")?,
            ))
        })
        .collect()
}

/// A number of a JSON value, or an error naming it.
fn num(v: &Value, what: &str) -> Result<f64> {
    v.as_f64()
        .ok_or_else(|| anyhow!("results.json: {what} is not a number"))
}

/// A string of a JSON value, or an error naming it.
fn text<'a>(v: &'a Value, what: &str) -> Result<&'a str> {
    v.as_str()
        .ok_or_else(|| anyhow!("results.json: {what} is not a string"))
}

/// An array of a JSON value, or an error naming it.
fn list<'a>(v: &'a Value, what: &str) -> Result<&'a Vec<Value>> {
    v.as_array()
        .ok_or_else(|| anyhow!("results.json: {what} is not a list"))
}

/// The plot's name of a test, sampler or builder.
fn label(name: &str) -> &str {
    match name {
        "watertight" => "watertight (meshtrace)",
        "moller_trumbore" => "Moller-Trumbore f32",
        "moller_trumbore_f64" => "Moller-Trumbore f64 (seed)",
        "baldwin_weber" => "Baldwin-Weber",
        "conservative_slab" => "conservative slab (meshtrace)",
        "seed_slab" => "seed's slab",
        "williams" => "Williams et al.",
        "meshtrace_sphere" => "meshtrace sphere",
        "seed_cube" => "seed: cube, normalised",
        "seed_rejection" => "seed: rejection",
        "meshtrace_cosine" => "meshtrace cosine",
        "seed_diffuse_cube" => "seed diffuse, cube",
        "seed_diffuse_rejection" => "seed diffuse, rejection",
        "seed_diffuse_rejection_down" => "seed diffuse, rejection, normal -z",
        "seed_cube_mt" => "seed: cube, normalised, mt19937",
        "seed_rejection_mt" => "seed: rejection, mt19937",
        "seed_diffuse_cube_mt" => "seed diffuse, cube, mt19937",
        "seed_diffuse_rejection_mt" => "seed diffuse, rejection, mt19937",
        "seed_midpoint" => "seed midpoint",
        "object_median" => "object median",
        "sah_fast" => "binned SAH (fast)",
        "sah_precise" => "binned SAH (precise)",
        other => other,
    }
}

/// The colour of the `k`-th of `n` things: viridis, from dark blue to yellow-green.
fn colour(k: usize, n: usize) -> RGBColor {
    let t = if n <= 1 {
        0.3
    } else {
        0.1 + 0.7 * k as f32 / (n - 1) as f32
    };
    let [r, g, b] = viridis(t);
    RGBColor(r, g, b)
}

/// A plot's pixels, drawn by `draw` and written to `path` as a PNG.
fn plot(path: &Path, (w, h): (u32, u32), draw: impl FnOnce(&Area) -> Result<()>) -> Result<()> {
    register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow!("the bundled font does not load"))?;
    let mut rgb = vec![255u8; 3 * w as usize * h as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root)?;
        root.present()
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    }
    let image = image::RgbImage::from_raw(w, h, rgb).ok_or_else(|| anyhow!("buffer size"))?;
    let mut bytes = Vec::new();
    image.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )?;
    meshtrace::film::write_bytes(path, &bytes)?;
    println!("<!-- wrote {} -->", path.display());
    Ok(())
}

/// plotters' errors as anyhow's.
fn drawn<T, E: std::fmt::Display>(r: std::result::Result<T, E>) -> Result<T> {
    r.map_err(|e| anyhow!("drawing: {e}"))
}

fn font(size: u32) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

/// One set of bars: a value per group, in one colour or one per group.
struct Bars {
    name: String,
    values: Vec<f64>,
    colours: Vec<RGBColor>,
    /// A range per bar (quartiles), drawn as a whisker; empty for none.
    spread: Vec<(f64, f64)>,
}

/// A panel of grouped bars, each labelled with its value by `fmt`, the groups named under
/// the axis (on `root`, the whole plot, where the panel's clipping does not reach), and a
/// legend where there is more than one set.
fn bar_panel(
    root: &Area,
    panel: &Area,
    title: &str,
    y_desc: &str,
    groups: &[String],
    sets: &[Bars],
    fmt: &dyn Fn(f64) -> String,
) -> Result<()> {
    let top = sets
        .iter()
        .flat_map(|s| {
            s.values
                .iter()
                .chain(s.spread.iter().map(|r| &r.1))
                .copied()
        })
        .fold(0.0f64, f64::max)
        .max(1e-9);
    let legend = sets.len() > 1;
    let y_max = top * if legend { 1.45 } else { 1.18 };
    let n = groups.len() as f64;
    let mut chart = drawn(
        ChartBuilder::on(panel)
            .caption(title, font(17))
            .margin(10)
            .margin_bottom(48)
            .x_label_area_size(8)
            .y_label_area_size(62)
            .build_cartesian_2d(-0.5..n - 0.5, 0.0..y_max),
    )?;
    drawn(
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_labels(0)
            .x_label_formatter(&|_| String::new())
            .y_desc(y_desc)
            .y_label_formatter(&|v| fmt_axis(*v))
            .label_style(font(12))
            .axis_desc_style(font(13))
            .draw(),
    )?;
    let width = 0.8 / sets.len() as f64;
    for (k, set) in sets.iter().enumerate() {
        let colours = set.colours.clone();
        let x0 = |g: usize| g as f64 - 0.4 + k as f64 * width;
        let series = drawn(
            chart.draw_series(set.values.iter().enumerate().map(|(g, &v)| {
                let c = colours[g.min(colours.len() - 1)];
                Rectangle::new([(x0(g) + 0.02, 0.0), (x0(g) + width - 0.02, v)], c.filled())
            })),
        )?;
        if legend {
            let c = set.colours[0];
            series
                .label(set.name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
        }
        for (g, &v) in set.values.iter().enumerate() {
            let centre = x0(g) + width / 2.0;
            let mut label_at = v;
            if let Some(&(lo, hi)) = set.spread.get(g) {
                drawn(chart.draw_series([PathElement::new(
                    vec![(centre, lo), (centre, hi)],
                    BLACK.stroke_width(2),
                )]))?;
                label_at = label_at.max(hi);
            }
            let (px, py) = chart.backend_coord(&(centre, label_at));
            let style = font(11).pos(Pos::new(HPos::Center, VPos::Bottom));
            drawn(root.draw(&Text::new(fmt(v), (px, py - 2), style)))?;
        }
    }
    for (g, name) in groups.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(g as f64, 0.0));
        let style = font(12).pos(Pos::new(HPos::Center, VPos::Top));
        for (line, part) in name.split('\n').enumerate() {
            drawn(root.draw(&Text::new(
                part.to_string(),
                (px, py + 6 + 15 * line as i32),
                style.clone(),
            )))?;
        }
    }
    if legend {
        drawn(
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .label_font(font(12))
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK.mix(0.4))
                .draw(),
        )?;
    }
    Ok(())
}

/// An axis value, short.
fn fmt_axis(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 10.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// A value with three significant digits.
fn sig3(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// Names of more than 14 characters wrapped at the space nearest their middle, for the
/// group labels.
fn wrap(name: &str) -> String {
    let middle = name.len() / 2;
    let space = name
        .char_indices()
        .filter(|&(_, c)| c == ' ')
        .min_by_key(|&(i, _)| i.abs_diff(middle));
    match space {
        Some((i, _)) if name.len() > 14 => format!("{}\n{}", &name[..i], &name[i + 1..]),
        _ => name.to_string(),
    }
}

fn main() -> Result<()> {
    let inputs = Inputs::load()?;
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/algorithms");
    std::fs::create_dir_all(&out).with_context(|| format!("{}", out.display()))?;
    let machine = inputs.measure("machine")?;
    println!(
        "Machine: {} ({} threads).\n",
        text(&machine["cpu"], "machine.cpu")?,
        machine["threads"]
    );
    triangles(&inputs, &out)?;
    escapes(&inputs, &out)?;
    boxes(&inputs, &out)?;
    samplers(&inputs, &out)?;
    densities(&inputs, &out)?;
    bvh(&inputs, &out)?;
    paired(&inputs)
}

/// The paired ratios of the bench's `paired` measure, as a table.
fn paired(inputs: &Inputs) -> Result<()> {
    let p = inputs.measure("paired")?;
    println!("| comparison | variant | time / reference's: median | quartiles |");
    println!("|---|---|---|---|");
    let row = |what: &str, g: &Value| -> Result<()> {
        let reference = text(&g["reference"], "paired.reference")?;
        let ratios = g["ratios"]
            .as_object()
            .ok_or_else(|| anyhow!("results.json: paired ratios are not a map"))?;
        for (name, r) in ratios {
            if name != reference {
                println!(
                    "| {what}, against {} | {} | {:.3} | {:.3} to {:.3} |",
                    label(reference),
                    label(name),
                    num(&r["median"], "median")?,
                    num(&r["q1"], "q1")?,
                    num(&r["q3"], "q3")?
                );
            }
        }
        Ok(())
    };
    for (key, what) in [
        ("unit", "unit vector, SplitMix64"),
        ("bounce", "diffuse bounce, SplitMix64"),
        ("unit_mt", "unit vector, mt19937"),
        ("bounce_mt", "diffuse bounce, mt19937"),
    ] {
        row(what, &p["samplers"][key])?;
    }
    row("candidate triangle tests", &p["triangle_pairs"])?;
    row("closest-hit traversal", &p["triangle_traversal"])?;
    row("candidate box tests", &p["box_pairs"])?;
    row("BVH build", &p["bvh_build"])?;
    row("BVH traversal", &p["bvh_traversal"])?;
    println!();
    Ok(())
}

const TRI_TESTS: [&str; 4] = [
    "watertight",
    "moller_trumbore",
    "moller_trumbore_f64",
    "baldwin_weber",
];

/// Plot 1: the triangle tests' speed, alone and in traversals.
fn triangles(inputs: &Inputs, out: &Path) -> Result<()> {
    let mesh = inputs.measure("speed_mesh")?;
    let mesh_name = text(&mesh["name"], "speed_mesh.name")?;
    let ns: Vec<f64> = TRI_TESTS
        .iter()
        .map(|t| inputs.ns_per("triangle_pairs", t))
        .collect::<Result<_>>()?;
    let rays: Vec<f64> = TRI_TESTS
        .iter()
        .map(|t| inputs.mrate("triangle_traversal", t))
        .collect::<Result<_>>()?;
    println!(
        "| triangle test | ns per candidate test | ratio to watertight | closest-hit Mrays/s ({mesh_name}) | ratio |"
    );
    println!("|---|---|---|---|---|");
    for (i, t) in TRI_TESTS.iter().enumerate() {
        println!(
            "| {} | {:.2} | {:.2} | {:.3} | {:.2} |",
            label(t),
            ns[i],
            ns[i] / ns[0],
            rays[i],
            rays[i] / rays[0]
        );
    }
    println!();
    let traversal = paired_ratios(inputs, &["triangle_traversal"], &TRI_TESTS)?;
    let groups: Vec<String> = TRI_TESTS.iter().map(|t| wrap(label(t))).collect();
    let colours: Vec<RGBColor> = (0..4).map(|k| colour(k, 4)).collect();
    plot(&out.join("triangle_speed.png"), (1100, 460), |root| {
        let panels = root.split_evenly((1, 2));
        bar_panel(
            root,
            &panels[0],
            "Candidate tests from traversals (lower is faster)",
            "ns per test",
            &groups,
            &[Bars {
                name: String::new(),
                values: ns.clone(),
                colours: colours.clone(),
                spread: Vec::new(),
            }],
            &|v| format!("{v:.2}"),
        )?;
        bar_panel(
            root,
            &panels[1],
            &format!("Closest-hit traversal time, {mesh_name}, paired"),
            "time / watertight's (median, quartiles)",
            &groups,
            &[Bars {
                name: String::new(),
                values: traversal.iter().map(|r| r.0).collect(),
                colours: colours.clone(),
                spread: traversal.iter().map(|r| (r.1, r.2)).collect(),
            }],
            &|v| format!("{v:.3}"),
        )
    })
}

/// Plot 2: rays that escape closed meshes through each test's cracks.
fn escapes(inputs: &Inputs, out: &Path) -> Result<()> {
    let meshes = list(inputs.measure("escapes")?, "escapes")?;
    let mut names = Vec::new();
    // [kind][test][mesh] percentages.
    let mut pct = vec![vec![Vec::new(); TRI_TESTS.len()]; 4];
    println!(
        "| mesh | triangles | rays at vertices / edges / interiors / random | test | escapes at vertices | at edges | at interiors | random |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for m in meshes {
        let name = text(&m["mesh"], "escapes.mesh")?;
        names.push(name.to_string());
        let rays: Vec<f64> = (0..4)
            .map(|k| num(&m["rays"][k], "escapes.rays"))
            .collect::<Result<_>>()?;
        for (t, test) in TRI_TESTS.iter().enumerate() {
            let mut cells = Vec::new();
            for k in 0..4 {
                let e = num(&m["escapes"][*test][k], "escapes.escapes")?;
                pct[k][t].push(100.0 * e / rays[k]);
                cells.push(format!("{e} ({:.3}%)", 100.0 * e / rays[k]));
            }
            println!(
                "| {name} | {} | {} / {} / {} / {} | {} | {} |",
                m["triangles"],
                rays[0],
                rays[1],
                rays[2],
                rays[3],
                label(test),
                cells.join(" | ")
            );
        }
    }
    println!();
    let sets = |kind: usize| -> Vec<Bars> {
        TRI_TESTS
            .iter()
            .enumerate()
            .map(|(t, test)| Bars {
                name: label(test).to_string(),
                values: pct[kind][t].clone(),
                colours: vec![colour(t, TRI_TESTS.len())],
                spread: Vec::new(),
            })
            .collect()
    };
    plot(&out.join("triangle_escapes.png"), (1100, 480), |root| {
        let panels = root.split_evenly((1, 2));
        for (p, (kind, what)) in [(0, "vertices"), (1, "edges")].into_iter().enumerate() {
            bar_panel(
                root,
                &panels[p],
                &format!("Rays from inside aimed at {what} that escape"),
                "% of rays",
                &names,
                &sets(kind),
                &|v| {
                    if v == 0.0 {
                        "0".into()
                    } else {
                        format!("{v:.1}")
                    }
                },
            )?;
        }
        Ok(())
    })
}

const BOX_TESTS: [&str; 3] = ["conservative_slab", "seed_slab", "williams"];

/// Plot 3: the box tests' speed and the boxes they miss.
fn boxes(inputs: &Inputs, out: &Path) -> Result<()> {
    let ns: Vec<f64> = BOX_TESTS
        .iter()
        .map(|t| inputs.ns_per("box_pairs", t))
        .collect::<Result<_>>()?;
    let rows = list(inputs.measure("box_misses")?, "box_misses")?;
    // [test][set]: (misses, cases) of the closed meshes together and of the Cornell box.
    let mut tally = [[(0.0, 0.0); 4]; 3];
    println!(
        "| box test | ns per test | ratio | mesh | missed, oblique rays | missed, axis-aligned rays |"
    );
    println!("|---|---|---|---|---|---|");
    for (t, test) in BOX_TESTS.iter().enumerate() {
        for r in rows {
            let mesh = text(&r["mesh"], "box_misses.mesh")?;
            let base = if mesh == "cornell" { 2 } else { 0 };
            let mut cells = Vec::new();
            for set in 0..2 {
                let m = num(&r["misses"][*test][set], "box_misses.misses")?;
                let c = num(&r["cases"][set], "box_misses.cases")?;
                tally[t][base + set].0 += m;
                tally[t][base + set].1 += c;
                cells.push(format!("{m} of {c} ({:.2}%)", 100.0 * m / c));
            }
            println!(
                "| {} | {:.2} | {:.2} | {mesh} | {} |",
                label(test),
                ns[t],
                ns[t] / ns[0],
                cells.join(" | ")
            );
        }
    }
    println!();
    let groups: Vec<String> = [
        "closed meshes\noblique",
        "closed meshes\naxis-aligned",
        "Cornell box\noblique",
        "Cornell box\naxis-aligned",
    ]
    .map(String::from)
    .to_vec();
    let sets: Vec<Bars> = BOX_TESTS
        .iter()
        .enumerate()
        .map(|(t, test)| Bars {
            name: label(test).to_string(),
            values: tally[t].iter().map(|(m, c)| 100.0 * m / c).collect(),
            colours: vec![colour(t, 3)],
            spread: Vec::new(),
        })
        .collect();
    let names: Vec<String> = BOX_TESTS.iter().map(|t| wrap(label(t))).collect();
    plot(&out.join("box_tests.png"), (1100, 480), |root| {
        let panels = root.split_evenly((1, 2));
        bar_panel(
            root,
            &panels[0],
            "Box tests from traversals (lower is faster)",
            "ns per test",
            &names,
            &[Bars {
                name: String::new(),
                values: ns.clone(),
                colours: (0..3).map(|k| colour(k, 3)).collect(),
                spread: Vec::new(),
            }],
            &|v| format!("{v:.2}"),
        )?;
        bar_panel(
            root,
            &panels[1],
            "Triangle hit, its box missed",
            "% of rays",
            &groups,
            &sets,
            &|v| {
                if v == 0.0 {
                    "0".into()
                } else {
                    format!("{v:.1}")
                }
            },
        )
    })
}

/// Plot 4: each sampler's speed against its chi-square bias.
fn samplers(inputs: &Inputs, out: &Path) -> Result<()> {
    let s = inputs.measure("samplers")?;
    let rows = list(&s["rows"], "samplers.rows")?;
    println!(
        "| sampler | ns per direction | chi-square | dof | chi-square / dof | log10 p | density near corners / faces (x uniform) |"
    );
    println!("|---|---|---|---|---|---|---|");
    // (name, ns or None when not timed, chi2 / dof)
    let mut points = Vec::new();
    for r in rows {
        let name = text(&r["name"], "samplers.name")?;
        let ns = inputs.ns_per("samplers", name).ok();
        let (chi2, dof) = (num(&r["chi2"], "chi2")?, num(&r["dof"], "dof")?);
        let density = match (r["corner_density"].as_f64(), r["face_density"].as_f64()) {
            (Some(c), Some(f)) => format!("{c:.3} / {f:.3}"),
            _ => "".into(),
        };
        println!(
            "| {} | {} | {:.1} | {dof} | {:.2} | {:.1} | {density} |",
            label(name),
            ns.map_or("(not timed)".into(), |v| format!("{v:.2}")),
            chi2,
            chi2 / dof,
            num(&r["log10_p"], "log10_p")?,
        );
        if let Some(ns) = ns {
            points.push((name.to_string(), ns, chi2 / dof));
        }
        // The same method drawing from the seed's mt19937, where it was timed so.
        if let Ok(ns) = inputs.ns_per("samplers", &format!("{name}_mt")) {
            println!("| {}, mt19937 | {ns:.2} | | | | | |", label(name));
            points.push((format!("{name}_mt"), ns, chi2 / dof));
        }
        if let Some(c) = r.get("against_cube_pdf") {
            println!(
                "| {} against the cube's own density | | {:.1} | {} | {:.2} | {:.1} | |",
                label(name),
                num(&c["chi2"], "chi2")?,
                c["dof"],
                num(&c["chi2"], "chi2")? / num(&c["dof"], "dof")?,
                num(&c["log10_p"], "log10_p")?
            );
        }
    }
    let replaced = &s["replaced_by_normal"];
    println!(
        "\nThe seed's diffuse bounce returns the normal itself for {:.1}% of bounces about +z, {:.1}% about -z, {:.1}% about (-1, -1, -1)/sqrt(3).\n",
        100.0 * num(&replaced["+z"], "+z")?,
        100.0 * num(&replaced["-z"], "-z")?,
        100.0 * num(&replaced["-x-y-z"], "-x-y-z")?
    );
    let ratio = |a: &str, b: &str| -> Result<f64> {
        Ok(inputs.ns_per("samplers", a)? / inputs.ns_per("samplers", b)?)
    };
    println!(
        "Rejection / cube time, SplitMix64: unit vector {:.2}, diffuse bounce {:.2}; mt19937: unit vector {:.2}, diffuse bounce {:.2}.\n",
        ratio("seed_rejection", "seed_cube")?,
        ratio("seed_diffuse_rejection", "seed_diffuse_cube")?,
        ratio("seed_rejection_mt", "seed_cube_mt")?,
        ratio("seed_diffuse_rejection_mt", "seed_diffuse_cube_mt")?
    );
    // The samplers in colour order.
    const BASES: [&str; 6] = [
        "meshtrace_sphere",
        "seed_cube",
        "seed_rejection",
        "meshtrace_cosine",
        "seed_diffuse_cube",
        "seed_diffuse_rejection",
    ];
    let x_max = points.iter().map(|p| p.1).fold(0.0, f64::max) * 1.15;
    let y_max = points.iter().map(|p| p.2).fold(1.0, f64::max) * 8.0;
    plot(&out.join("samplers.png"), (1200, 600), |root| {
        let mut chart = drawn(
            ChartBuilder::on(root)
                .caption(
                    "Direction samplers: time against bias (chi-square / dof; 1 is unbiased)",
                    font(17),
                )
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..x_max, (0.5..y_max).log_scale()),
        )?;
        drawn(
            chart
                .configure_mesh()
                .light_line_style(WHITE.mix(0.0))
                .x_desc("ns per direction (median)")
                .y_desc("chi-square / degrees of freedom")
                .y_label_formatter(&|v| sig3(*v))
                .label_style(font(12))
                .axis_desc_style(font(13))
                .draw(),
        )?;
        // The 1% critical level of 799 degrees of freedom, near 1.1 (399: 1.17).
        drawn(chart.draw_series([PathElement::new(
            vec![(0.0, 1.0), (x_max, 1.0)],
            BLACK.mix(0.3).stroke_width(1),
        )]))?;
        for (name, ns, bias) in &points {
            let (ns, bias) = (*ns, *bias);
            let base = name.strip_suffix("_mt");
            let k = BASES
                .iter()
                .position(|b| *b == base.unwrap_or(name))
                .unwrap_or(0);
            let c = colour(k, BASES.len());
            let style = if base.is_some() {
                c.stroke_width(2)
            } else {
                c.filled()
            };
            if name.contains("cosine") || name.contains("diffuse") {
                drawn(chart.draw_series([TriangleMarker::new((ns, bias), 9, style)]))?;
            } else {
                drawn(chart.draw_series([Circle::new((ns, bias), 7, style)]))?;
            }
            // Labels above and below, near and far in turn, in order of time in each row.
            let row = |p: &(String, f64, f64)| (p.2 < 10.0) == (bias < 10.0);
            let before = points.iter().filter(|p| row(p) && p.1 < ns).count();
            let (at, v) = match before % 4 {
                0 => (bias * 1.25, VPos::Bottom),
                1 => (bias / 1.25, VPos::Top),
                2 => (bias * 1.7, VPos::Bottom),
                _ => (bias / 1.7, VPos::Top),
            };
            let shown = match base {
                Some(base) => format!("{}, mt19937", label(base)),
                None => label(name).to_string(),
            };
            drawn(chart.draw_series([Text::new(
                format!("{shown} ({ns:.1} ns)"),
                (ns, at),
                font(12).pos(Pos::new(HPos::Center, v)),
            )]))?;
        }
        drawn(root.draw(&Text::new(
            "circles: uniform sphere; triangles: cosine hemisphere; hollow: the seed's mt19937 generator (else SplitMix64)",
            (90, 60),
            font(12),
        )))?;
        Ok(())
    })
}

/// Plot 5: where the seed's cube method puts its directions, against rejection's.
fn densities(inputs: &Inputs, out: &Path) -> Result<()> {
    let rows = list(&inputs.measure("samplers")?["rows"], "samplers.rows")?;
    let find = |name: &str| {
        rows.iter()
            .find(|r| r["name"] == name)
            .ok_or_else(|| anyhow!("results.json: no sampler {name}"))
    };
    let maps: Vec<(&str, usize, usize, Vec<f64>)> = ["seed_cube", "seed_rejection"]
        .into_iter()
        .map(|name| {
            let r = find(name)?;
            let cos_bins = num(&r["cells"]["cos_bins"], "cos_bins")? as usize;
            let phi_bins = num(&r["cells"]["phi_bins"], "phi_bins")? as usize;
            let d: Vec<f64> = list(&r["density"], "density")?
                .iter()
                .map(|v| num(v, "density"))
                .collect::<Result<_>>()?;
            if d.len() != cos_bins * phi_bins {
                bail!("results.json: {name}'s density has {} cells", d.len());
            }
            Ok((name, cos_bins, phi_bins, d))
        })
        .collect::<Result<_>>()?;
    const TOP: f64 = 3.0;
    plot(&out.join("cube_density.png"), (1100, 470), |root| {
        let (maps_area, bar) = root.split_horizontally(1000);
        let panels = maps_area.split_evenly((1, 2));
        for (p, (name, cos_bins, phi_bins, d)) in maps.iter().enumerate() {
            let mut chart = drawn(
                ChartBuilder::on(&panels[p])
                    .caption(format!("{}: density / uniform", label(name)), font(16))
                    .margin(12)
                    .x_label_area_size(40)
                    .y_label_area_size(52)
                    .build_cartesian_2d(0.0..360.0, -1.0..1.0),
            )?;
            drawn(
                chart
                    .configure_mesh()
                    .disable_mesh()
                    .x_desc("phi (degrees)")
                    .y_desc("cos theta")
                    .x_labels(9)
                    .label_style(font(12))
                    .axis_desc_style(font(13))
                    .draw(),
            )?;
            let (dp, dc) = (360.0 / *phi_bins as f64, 2.0 / *cos_bins as f64);
            drawn(chart.draw_series((0..d.len()).map(|cell| {
                let (c, ph) = ((cell / phi_bins) as f64, (cell % phi_bins) as f64);
                let [r, g, b] = viridis((d[cell] / TOP) as f32);
                Rectangle::new(
                    [
                        (ph * dp, -1.0 + c * dc),
                        ((ph + 1.0) * dp, -1.0 + (c + 1.0) * dc),
                    ],
                    RGBColor(r, g, b).filled(),
                )
            })))?;
            // The cube's corners (circles) and face centres (crosses).
            let k = 1.0 / 3f64.sqrt();
            let corners = [45.0, 135.0, 225.0, 315.0]
                .into_iter()
                .flat_map(|phi| [(phi, k), (phi, -k)]);
            drawn(chart.draw_series(corners.map(|p| Circle::new(p, 6, WHITE.stroke_width(2)))))?;
            let faces = [
                (0.0, 0.0),
                (90.0, 0.0),
                (180.0, 0.0),
                (270.0, 0.0),
                (360.0, 0.0),
            ];
            drawn(chart.draw_series(faces.map(|p| Cross::new(p, 6, RED.stroke_width(2)))))?;
        }
        // The colour bar.
        let (x0, top, bottom) = (20i32, 60i32, 400i32);
        for y in top..bottom {
            let t = (bottom - 1 - y) as f32 / (bottom - 1 - top) as f32;
            let [r, g, b] = viridis(t);
            drawn(bar.draw(&Rectangle::new(
                [(x0, y), (x0 + 18, y + 1)],
                RGBColor(r, g, b).filled(),
            )))?;
        }
        for k in 0..=6 {
            let v = TOP * k as f64 / 6.0;
            let y = bottom - 1 - ((bottom - 1 - top) * k) / 6;
            drawn(bar.draw(&Text::new(format!("{v:.1}"), (x0 + 24, y - 6), font(12))))?;
        }
        drawn(bar.draw(&Text::new("x uniform", (4, 30), font(12))))?;
        Ok(())
    })
}

const BUILDERS: [&str; 4] = ["seed_midpoint", "object_median", "sah_fast", "sah_precise"];

/// Plot 6: the BVH builds' SAH cost, build rate and traversal rate.
fn bvh(inputs: &Inputs, out: &Path) -> Result<()> {
    let rows = list(inputs.measure("bvh")?, "bvh")?;
    let mesh = inputs.measure("speed_mesh")?;
    let mesh_name = text(&mesh["name"], "speed_mesh.name")?;
    let mut cost = Vec::new();
    let mut build = Vec::new();
    let mut trace = Vec::new();
    println!(
        "| builder ({mesh_name}) | SAH cost | nodes | leaves | mean leaf | depth | nodes + triangles per ray | build Mtris/s | traversal Mrays/s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for b in BUILDERS {
        let r = rows
            .iter()
            .find(|r| r["name"] == b)
            .ok_or_else(|| anyhow!("results.json: no tree {b}"))?;
        cost.push(num(&r["sah_cost"], "sah_cost")?);
        build.push(inputs.mrate("bvh_build", b)?);
        trace.push(inputs.mrate("bvh_traversal", b)?);
        println!(
            "| {} | {:.2} | {} | {} | {:.2} | {} | {:.1} | {:.2} | {:.3} |",
            label(b),
            cost.last().copied().unwrap_or_default(),
            r["nodes"],
            r["leaves"],
            num(&r["mean_leaf"], "mean_leaf")?,
            r["depth"],
            num(&r["cost_per_ray"], "cost_per_ray")?,
            build.last().copied().unwrap_or_default(),
            trace.last().copied().unwrap_or_default(),
        );
    }
    println!();
    let traversal = paired_ratios(inputs, &["bvh_traversal"], &BUILDERS)?;
    let groups: Vec<String> = BUILDERS.iter().map(|b| wrap(label(b))).collect();
    let colours: Vec<RGBColor> = (0..4).map(|k| colour(k, 4)).collect();
    let one = |values: &Vec<f64>| {
        [Bars {
            name: String::new(),
            values: values.clone(),
            colours: colours.clone(),
            spread: Vec::new(),
        }]
    };
    plot(&out.join("bvh_builds.png"), (1350, 460), |root| {
        let panels = root.split_evenly((1, 3));
        bar_panel(
            root,
            &panels[0],
            "SAH cost (lower is better)",
            "expected tests per ray",
            &groups,
            &one(&cost),
            &|v| format!("{v:.2}"),
        )?;
        bar_panel(
            root,
            &panels[1],
            "Build rate, 1 thread",
            "million triangles per second",
            &groups,
            &one(&build),
            &|v| format!("{v:.2}"),
        )?;
        bar_panel(
            root,
            &panels[2],
            &format!("Closest-hit traversal time, {mesh_name}, paired"),
            "time / fast SAH tree's (median, quartiles)",
            &groups,
            &[Bars {
                name: String::new(),
                values: traversal.iter().map(|r| r.0).collect(),
                colours: colours.clone(),
                spread: traversal.iter().map(|r| (r.1, r.2)).collect(),
            }],
            &|v| format!("{v:.3}"),
        )
    })
}
