//! The tests of the whole crate, from its public entry points down to the tick labels.

use std::path::PathBuf;

use mls_shapes::{SurfacePoint, Torus, fibonacci_sphere, normals, points, random};

use super::*;
use crate::colour::RDBU;
use crate::splat::{LEGEND_BAND, PANEL_TITLE_BAND, TITLE_BAND, Ticks};
use crate::view::{Camera, dot};

const TORUS_SEED: u64 = 11;

/// Where the test figures go: a fresh temporary directory, or `$FIGURES_TEST_DIR` when set,
/// to look at them.
fn out_dir() -> (Option<tempfile::TempDir>, PathBuf) {
    match std::env::var_os("FIGURES_TEST_DIR") {
        Some(dir) => (None, PathBuf::from(dir)),
        None => {
            let dir = tempfile::tempdir().expect("temporary directory");
            let path = dir.path().to_path_buf();
            (Some(dir), path)
        }
    }
}

/// Width, height and RGB bytes of a PNG.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("PNG exists"));
    let mut reader = png::Decoder::new(file).read_info().expect("PNG header");
    let mut rgb = vec![0; reader.output_buffer_size().expect("buffer size")];
    let info = reader.next_frame(&mut rgb).expect("PNG data");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    rgb.truncate(info.buffer_size());
    (info.width, info.height, rgb)
}

/// Whether some pixel in the `half`-pixel square around (x, y) has a colour: neither the
/// background nor any grey.
fn coloured_near(image: &(u32, u32, Vec<u8>), (x, y): (u32, u32), half: u32) -> bool {
    let (width, _, rgb) = image;
    (y - half..y + half).any(|y| {
        (x - half..x + half).any(|x| {
            let i = 3 * (y * width + x) as usize;
            let [r, g, b] = [rgb[i], rgb[i + 1], rgb[i + 2]];
            !(r == g && g == b)
        })
    })
}

fn file_size(path: &Path) -> u64 {
    std::fs::metadata(path).expect("PNG exists").len()
}

#[test]
fn sphere_coloured_by_height_is_a_coloured_ball() {
    let (_keep, dir) = out_dir();
    let path = dir.join("sphere.png");
    let sphere = fibonacci_sphere(4000, 1.0);
    let (p, n) = (points(&sphere), normals(&sphere));
    let z: Vec<f64> = p.iter().map(|p| p[2]).collect();
    let scale = ColourScale {
        min: -1.0,
        max: 1.0,
        label: "z".to_owned(),
        kind: ScaleKind::Sequential,
    };
    let title = "Unit sphere, 4000 points, coloured by height";
    let cloud = Cloud {
        points: &p,
        normals: Some(&n),
    };
    splat_png(
        &path,
        title,
        cloud,
        &z,
        &scale,
        View::THREE_QUARTER,
        (600, 500),
    )
    .expect("figure written");
    let image = decode(&path);
    assert_eq!((image.0, image.1), (600, 500));
    // The render area lies between the title band and the legend band.
    let centre = (300, (TITLE_BAND + 500 - LEGEND_BAND) / 2);
    assert!(
        coloured_near(&image, centre, 5),
        "no colour at the sphere's centre"
    );
    assert!(file_size(&path) < 300_000, "{} bytes", file_size(&path));
}

#[test]
fn torus_panels_with_diverging_and_missing_values() {
    let (_keep, dir) = out_dir();
    let path = dir.join("torus.png");
    let torus: Vec<SurfacePoint> = random(&Torus::new(1.0, 0.4), 12_000, TORUS_SEED)
        .iter()
        .map(|s| s.surface)
        .collect();
    let (p, n) = (points(&torus), normals(&torus));
    let gauss: Vec<f64> = torus.iter().map(SurfacePoint::gauss).collect();
    // The mean curvature, missing on the quarter x > 0, y > 0 as a failed region would be.
    let mean: Vec<f64> = torus
        .iter()
        .map(|s| {
            let missing = s.point.x > 0.0 && s.point.y > 0.0;
            if missing { f64::NAN } else { s.mean() }
        })
        .collect();
    let panels = [
        Panel {
            title: "Gaussian curvature K".to_owned(),
            legend: ColourScale::robust_symmetric(&gauss, "K").into(),
            values: gauss,
        },
        Panel {
            title: "Mean curvature H, a quarter missing".to_owned(),
            legend: ColourScale::robust_sequential(&mean, "H").into(),
            values: mean,
        },
    ];
    let title = "Torus R = 1, r = 0.4, 12000 random points";
    let cloud = Cloud {
        points: &p,
        normals: Some(&n),
    };
    splat_panels_png(
        &path,
        title,
        cloud,
        &panels,
        View::THREE_QUARTER,
        (600, 500),
        2,
    )
    .expect("figure written");
    let image = decode(&path);
    assert_eq!((image.0, image.1), (1200, 500 + TITLE_BAND));
    // The torus's outer rim, left of the hole, in the first panel.
    let render_mid = TITLE_BAND + (PANEL_TITLE_BAND + 500 - LEGEND_BAND) / 2;
    assert!(
        coloured_near(&image, (110, render_mid), 20),
        "no colour on the torus"
    );
    assert!(file_size(&path) < 600_000, "{} bytes", file_size(&path));
}

#[test]
fn line_chart_with_log_axes() {
    let (_keep, dir) = out_dir();
    let path = dir.join("chart.png");
    let density: [f64; 7] = [250.0, 500.0, 1000.0, 2000.0, 4000.0, 8000.0, 16000.0];
    let series = |name: &str, c: f64, order: f64| Series {
        name: name.to_owned(),
        points: density
            .iter()
            .map(|&d| (d, c * d.powf(-order / 2.0)))
            .collect(),
    };
    let all = [
        series("k1, closed form", 3.0, 2.0),
        series("k2, closed form", 5.0, 2.0),
        series("k1, normals estimated", 2.0, 1.0),
        Series {
            name: "one NaN".to_owned(),
            points: vec![(300.0, 0.1), (600.0, f64::NAN), (1200.0, 0.05)],
        },
    ];
    line_chart_png(
        &path,
        "Curvature error against sampling density",
        &Axis::log("points on the surface"),
        &Axis::log("max |error| / |k|"),
        &all,
        (700, 500),
    )
    .expect("chart written");
    let image = decode(&path);
    assert_eq!((image.0, image.1), (700, 500));
    assert!(file_size(&path) < 100_000, "{} bytes", file_size(&path));

    let linear = dir.join("chart-linear.png");
    let (x, y) = (Axis::linear("x"), Axis::linear("y"));
    line_chart_png(&linear, "Linear", &x, &y, &all[..1], (500, 400)).expect("linear chart written");
    assert_eq!(decode(&linear).0, 500);
}

#[test]
fn empty_or_valueless_input_is_an_error_or_grey_not_a_panic() {
    let (_keep, dir) = out_dir();
    let path = dir.join("empty.png");
    let scale = ColourScale::robust_symmetric(&[], "nothing");
    assert_eq!((scale.min, scale.max), (-1.0, 1.0));
    let view = View::THREE_QUARTER;
    let empty = Cloud {
        points: &[],
        normals: None,
    };
    let error = splat_png(&path, "empty", empty, &[], &scale, view, (300, 300))
        .expect_err("nothing to draw");
    assert!(format!("{error:#}").contains("no points"), "{error:#}");
    let axis = Axis::log("x");
    let chart = line_chart_png(&path, "t", &axis, &axis, &[], (300, 300));
    assert!(chart.is_err());
    assert!(!path.exists());

    // All values missing: a grey render; one point: a disc; no normals: flat colours.
    let sphere = points(&fibonacci_sphere(500, 1.0));
    let cloud = Cloud {
        points: &sphere,
        normals: None,
    };
    let nan = vec![f64::NAN; sphere.len()];
    let nan_path = dir.join("all-nan.png");
    splat_png(
        &nan_path,
        "no values",
        cloud,
        &nan,
        &scale,
        view,
        (300, 300),
    )
    .expect("grey figure");
    assert_eq!(decode(&nan_path).0, 300);
    let one = Cloud {
        points: &sphere[..1],
        normals: None,
    };
    splat_png(
        &dir.join("one.png"),
        "",
        one,
        &[0.5],
        &scale,
        view,
        (300, 300),
    )
    .expect("one point");

    // Mismatched lengths and a bad scale are errors naming the problem.
    let short = splat_png(&path, "t", cloud, &[1.0], &scale, view, (300, 300));
    assert!(short.is_err());
    let bad = ColourScale {
        min: 1.0,
        max: 1.0,
        ..scale
    };
    let zero = vec![0.0; sphere.len()];
    let flat = splat_png(&path, "t", cloud, &zero, &bad, view, (300, 300));
    assert!(format!("{:#}", flat.expect_err("empty range")).contains("min < max"));
}

#[test]
fn views_look_from_the_named_axis_and_keep_the_up_axis_up() {
    assert_eq!(View::parse("-60, 30", Up::Z), Ok(View::THREE_QUARTER));
    let axes = [
        ("+x", [1.0, 0.0, 0.0]),
        ("-x", [-1.0, 0.0, 0.0]),
        ("+y", [0.0, 1.0, 0.0]),
        ("-y", [0.0, -1.0, 0.0]),
        ("+z", [0.0, 0.0, 1.0]),
        ("-z", [0.0, 0.0, -1.0]),
    ];
    for up in [Up::X, Up::Y, Up::Z] {
        let up_axis = up.to_world([0.0, 0.0, 1.0]);
        for (spec, direction) in axes {
            let view = View::parse(spec, up).expect("a named view");
            let camera = Camera::new(view);
            let toward = dot(&camera.toward, &direction);
            assert!((toward - 1.0).abs() < 1e-12, "{spec} {up:?}: {toward}");
            // Screen up is the up axis unless the camera looks along it.
            let along = dot(&direction, &up_axis).abs() > 0.5;
            let upright = dot(&camera.up, &up_axis);
            assert!(along || (upright - 1.0).abs() < 1e-12, "{spec} {up:?}");
            // A right-handed screen: right × up = toward.
            let [r, u] = [camera.right, camera.up];
            let cross = [
                r[1] * u[2] - r[2] * u[1],
                r[2] * u[0] - r[0] * u[2],
                r[0] * u[1] - r[1] * u[0],
            ];
            assert!((dot(&cross, &camera.toward) - 1.0).abs() < 1e-12, "{spec}");
        }
    }
    for bad in ["sideways", "10,95", "1,2,3", "", "nan,0"] {
        let error = View::parse(bad, Up::Z).expect_err(bad);
        assert!(error.contains("view"), "{error}");
    }
}

#[test]
fn categories_colour_their_points_and_have_swatches() {
    let sphere = fibonacci_sphere(2000, 1.0);
    let (p, n) = (points(&sphere), normals(&sphere));
    // Category 0 on the upper half, 5 on the lower, and one value of no category.
    let mut codes: Vec<f64> = p
        .iter()
        .map(|p| if p[2] > 0.0 { 0.0 } else { 5.0 })
        .collect();
    codes[0] = 9.0;
    let (blue, orange) = ([0x56, 0xb4, 0xe9], [0xd5, 0x5e, 0x00]);
    let categories = vec![
        Category {
            value: 0.0,
            label: "0 ok".to_owned(),
            colour: blue,
        },
        Category {
            value: 5.0,
            label: "5 failed".to_owned(),
            colour: orange,
        },
    ];
    let panel = Panel {
        title: String::new(),
        values: codes,
        legend: Legend::Categories(categories),
    };
    let cloud = Cloud {
        points: &p,
        normals: Some(&n),
    };
    let image = render(
        "",
        cloud,
        &[panel],
        View::parse("+y", Up::Z).unwrap(),
        (500, 400),
        1,
    )
    .expect("figure");
    assert_eq!((image.width(), image.height()), (500, 400));
    let count = |colour: Rgb, rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..500).map(move |x| (x, y)))
            .filter(|&(x, y)| image.pixel(x, y) == Some(colour))
            .count()
    };
    // Swatches of 14 × 14 pixels, less their frame, in the legend band.
    let band = 400 - LEGEND_BAND..400;
    assert!(
        count(blue, band.clone()) >= 150,
        "{}",
        count(blue, band.clone())
    );
    assert!(count(orange, band.clone()) >= 150);
    assert!(count(NO_VALUE, band) >= 50, "the no-value swatch");
    // Shaded points: hues of blue above the middle of the render, of orange below.
    let hue = |y: u32, pick: fn(Rgb) -> bool| {
        (150..350)
            .filter(|&x| image.pixel(x, y).is_some_and(pick))
            .count()
    };
    let bluish = |c: Rgb| i32::from(c[2]) > i32::from(c[0]) + 40;
    let orangish = |c: Rgb| i32::from(c[0]) > i32::from(c[2]) + 60;
    assert!(hue(100, bluish) > 100 && hue(100, orangish) == 0);
    assert!(hue(220, orangish) > 100 && hue(220, bluish) == 0);
}

#[test]
fn robust_ranges_ignore_a_few_outliers() {
    let mut values: Vec<f64> = (0..1000).map(|i| f64::from(i) / 1000.0 - 0.5).collect();
    values.extend([1e6, -1e6, f64::NAN, f64::INFINITY]);
    let symmetric = ColourScale::robust_symmetric(&values, "error");
    assert_eq!(symmetric.min, -symmetric.max);
    assert!((0.45..0.5).contains(&symmetric.max), "{symmetric:?}");
    let sequential = ColourScale::robust_sequential(&values, "k");
    assert!((-0.5..-0.45).contains(&sequential.min), "{sequential:?}");
    assert!((0.45..0.5).contains(&sequential.max), "{sequential:?}");
    let constant = ColourScale::robust_sequential(&[2.0; 10], "k");
    assert_eq!((constant.min, constant.max), (1.5, 2.5));
}

#[test]
fn diverging_scale_is_white_at_zero_and_ticks_are_round() {
    let scale = ColourScale {
        min: -1.0,
        max: 3.0,
        label: String::new(),
        kind: ScaleKind::Diverging,
    };
    assert_eq!(scale.colour(0.0), Some(RDBU[4]));
    assert_eq!(scale.colour(-5.0), Some(RDBU[0]));
    assert_eq!(scale.colour(3.0), Some(RDBU[8]));
    assert_eq!(scale.colour(f64::NAN), None);

    let ticks = Ticks::new(-2.5e-6, 2.5e-6);
    assert_eq!(ticks.exponent, -6);
    let labels: Vec<String> = ticks.values.iter().map(|&v| ticks.label(v)).collect();
    assert_eq!(labels, ["-2", "-1", "0", "1", "2"]);
    let ticks = Ticks::new(0.0, 0.35);
    let labels: Vec<String> = ticks.values.iter().map(|&v| ticks.label(v)).collect();
    assert_eq!(labels, ["0.0", "0.1", "0.2", "0.3"]);
}
