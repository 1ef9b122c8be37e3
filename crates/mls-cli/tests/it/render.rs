//! `mlscurv render`: the picture's size, colours where the values are known (a plane whose
//! left third bends one way, right third the other, middle third failed), the colour bar,
//! the status legend, and the errors.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use crate::common::{assert_one_line_error, listing, mlscurv, run, run_ok, write_unit_sphere};

/// A decoded PNG: width, height, RGB rows from the top.
struct Picture {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Picture {
    fn read(path: &Path) -> Self {
        let file = std::io::BufReader::new(fs::File::open(path).expect("PNG exists"));
        let mut reader = png::Decoder::new(file).read_info().expect("PNG header");
        let mut rgb = vec![0; reader.output_buffer_size().expect("buffer size")];
        let info = reader.next_frame(&mut rgb).expect("PNG data");
        assert_eq!(info.color_type, png::ColorType::Rgb);
        rgb.truncate(info.buffer_size());
        Self {
            width: info.width,
            height: info.height,
            rgb,
        }
    }

    fn at(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y * self.width + x) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Counts of warm, cool and grey (not white) pixels in columns `xs` and rows `ys`.
    fn census(&self, xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> Census {
        let mut c = Census::default();
        for y in ys {
            for x in xs.clone() {
                match kind(self.at(x, y)) {
                    Kind::Warm => c.warm += 1,
                    Kind::Cool => c.cool += 1,
                    Kind::Grey => c.grey += 1,
                    Kind::Other => {}
                }
            }
        }
        c
    }
}

#[derive(Debug, Default)]
struct Census {
    warm: usize,
    cool: usize,
    grey: usize,
}

enum Kind {
    Warm,
    Cool,
    Grey,
    Other,
}

/// Warm: clearly more red than blue; cool: the reverse; grey: equal channels, not white.
fn kind([r, g, b]: [u8; 3]) -> Kind {
    let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
    if r == g && g == b && r < 250 {
        Kind::Grey
    } else if r > b + 40 {
        Kind::Warm
    } else if b > r + 40 {
        Kind::Cool
    } else {
        Kind::Other
    }
}

/// Height of the legend band under the render, and of the title band above it (mls-render).
const LEGEND_BAND: u32 = 78;
const TITLE_BAND: u32 = 40;

/// A result table as `curvature` writes it, on the plane z = 0 over [-1, 1]²: mean, k1, k2
/// and gauss negative on the left third, positive on the right third; the middle third
/// failed (status 5, NaN numbers and normals).
fn write_plane_result(path: &Path) {
    let mut text = String::from("x,y,z,nx,ny,nz,k1,k2,mean,gauss,status\n");
    let n = 41;
    for i in 0..n {
        for j in 0..n {
            let x = -1.0 + 2.0 * f64::from(i) / f64::from(n - 1);
            let y = -1.0 + 2.0 * f64::from(j) / f64::from(n - 1);
            let row = if x < -1.0 / 3.0 {
                "0,0,1,-0.5,-1.5,-1,0.75,0"
            } else if x > 1.0 / 3.0 {
                "0,0,1,1.5,0.5,1,0.75,0"
            } else {
                "NaN,NaN,NaN,NaN,NaN,NaN,NaN,5"
            };
            writeln!(text, "{x},{y},0,{row}").unwrap();
        }
    }
    fs::write(path, text).unwrap();
}

#[test]
fn plane_mean_is_cool_where_negative_warm_where_positive_grey_where_failed() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("plane.csv");
    write_plane_result(&input);
    let out = dir.path().join("plane-mean.png");
    // From above, x to the right.
    let r = run_ok(
        mlscurv()
            .arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["--field", "mean", "--view", "+z", "--size", "400x400"]),
    );
    assert!(r.stderr.contains("without a value"), "{}", r.stderr);
    let picture = Picture::read(&out);
    assert_eq!((picture.width, picture.height), (400, 400));

    // The square fills the render's height (282 px between the bands), centred: about 133 px
    // per unit, x = -1..1 at columns 67..333.
    let rows = TITLE_BAND + 40..400 - LEGEND_BAND - 40;
    let left = picture.census(85..140, rows.clone());
    let middle = picture.census(185..215, rows.clone());
    let right = picture.census(260..315, rows);
    let total = |c: &Census| c.warm + c.cool + c.grey;
    assert!(left.cool > 9 * total(&left) / 10, "left: {left:?}");
    assert!(right.warm > 9 * total(&right) / 10, "right: {right:?}");
    assert!(middle.grey > 9 * total(&middle) / 10, "middle: {middle:?}");
    assert!(total(&middle) > 1000, "middle: {middle:?}");

    // The colour bar: a row of the legend band that runs from cool on the left to warm on
    // the right through many colours.
    let bar = (400 - LEGEND_BAND..400).find(|&y| {
        let coloured: Vec<(u32, Kind)> = (0..400)
            .map(|x| (x, kind(picture.at(x, y))))
            .filter(|(_, k)| matches!(k, Kind::Warm | Kind::Cool))
            .collect();
        coloured.len() > 150
            && matches!(coloured.first(), Some((_, Kind::Cool)))
            && matches!(coloured.last(), Some((_, Kind::Warm)))
    });
    assert!(bar.is_some(), "no colour bar in the legend band");
    // Nothing coloured in the title band.
    let title = picture.census(0..400, 0..TITLE_BAND);
    assert_eq!((title.warm, title.cool), (0, 0), "{title:?}");
}

#[test]
fn status_is_drawn_as_categories_with_a_legend() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("plane.csv");
    write_plane_result(&input);
    let out = dir.path().join("plane-status.png");
    run_ok(
        mlscurv()
            .arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args([
                "--field", "status", "--view", "+z", "--size", "500x400", "-q",
            ]),
    );
    let picture = Picture::read(&out);
    assert_eq!((picture.width, picture.height), (500, 400));
    // Ok points sky blue (cool), failed ones (5, projection_failed) vermillion (warm), in the
    // render and in the legend's swatches.
    let rows = TITLE_BAND + 40..400 - LEGEND_BAND - 40;
    let left = picture.census(130..180, rows.clone());
    let middle = picture.census(235..265, rows);
    assert!(left.cool > 1000, "ok points: {left:?}");
    assert!(middle.warm > 700, "failed points: {middle:?}");
    let legend = picture.census(0..500, 400 - LEGEND_BAND..400);
    assert!(
        legend.cool >= 100 && legend.warm >= 100,
        "legend: {legend:?}"
    );
}

#[test]
fn curvature_result_of_a_sphere_is_warm() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sphere.xyz");
    write_unit_sphere(&input, 2000);
    let result = dir.path().join("sphere.ply");
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&result)
            .arg("-q"),
    );
    for (field, size) in [("mean", (300, 300)), ("gauss", (320, 260))] {
        let out = dir.path().join(format!("{field}.png"));
        run_ok(
            mlscurv()
                .arg("render")
                .arg(&result)
                .arg("-o")
                .arg(&out)
                .args(["--field", field, "-q", "--size"])
                .arg(format!("{}x{}", size.0, size.1)),
        );
        let picture = Picture::read(&out);
        assert_eq!((picture.width, picture.height), size);
        // Outward normals: mean = 1/R and gauss = 1/R² everywhere, the warm end.
        let (w, h) = size;
        let centre = picture.census(w / 2 - 20..w / 2 + 20, h / 2 - 30..h / 2 + 10);
        assert!(
            centre.warm > 1000 && centre.cool == 0,
            "{field}: {centre:?}"
        );
    }
}

#[test]
fn missing_field_names_the_file_and_its_columns() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("points.csv");
    fs::write(&input, "x,y,z,k1\n0,0,0,1\n1,0,0,1\n0,1,0,1\n").unwrap();
    let out = dir.path().join("out.png");
    let before = listing(dir.path());
    let r = run(mlscurv()
        .arg("render")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--field", "mean"]));
    assert_one_line_error(
        &r,
        &input.display().to_string(),
        &["no column `mean`", "it has x, y, z, k1"],
    );
    assert_eq!(listing(dir.path()), before, "nothing written");
}

#[test]
fn bad_view_size_or_output_is_a_usage_error_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("plane.csv");
    write_plane_result(&input);
    let out = dir.path().join("out.png");
    let before = listing(dir.path());
    for (args, words) in [
        (
            &["--view", "sideways"][..],
            &["--view", "sideways", "+x"][..],
        ),
        (&["--view", "10,95"], &["elevation", "-90..90"]),
        (&["--size", "800"], &["--size", "WIDTHxHEIGHT"]),
        (&["--field", "curl"], &["--field", "curl"]),
    ] {
        let r = run(mlscurv()
            .arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(args));
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        for word in words {
            assert!(r.stderr.contains(word), "{args:?}: {}", r.stderr);
        }
    }
    let jpeg = dir.path().join("out.jpg");
    let r = run(mlscurv().arg("render").arg(&input).arg("-o").arg(&jpeg));
    assert_one_line_error(&r, &jpeg.display().to_string(), &[".png"]);
    assert_eq!(listing(dir.path()), before, "nothing written");
}

#[cfg(unix)]
#[test]
fn read_only_picture_is_refused_unless_forced() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("plane.csv");
    write_plane_result(&input);
    let out = dir.path().join("out.png");
    fs::write(&out, "keep me").unwrap();
    fs::set_permissions(&out, fs::Permissions::from_mode(0o444)).unwrap();
    let render = || {
        let mut cmd = mlscurv();
        cmd.arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["-q", "--size", "300x300"]);
        cmd
    };
    let r = run(&mut render());
    assert_one_line_error(&r, &out.display().to_string(), &["read-only", "--force"]);
    assert_eq!(fs::read_to_string(&out).unwrap(), "keep me");
    run_ok(render().arg("--force"));
    assert_eq!(Picture::read(&out).width, 300);
    let mode = fs::metadata(&out).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o444, "a replaced file keeps its permissions");
}

/// `--field k1_sd` is sequential: where the predicted error is small (left half of a plane)
/// the map's dark end, where it is large (right half) its bright end.
#[test]
fn predicted_error_is_dark_where_small_bright_where_large() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("plane-sd.csv");
    let mut text = String::from("x,y,z,nx,ny,nz,k1,k2,k1_sd,status\n");
    let n = 41;
    for i in 0..n {
        for j in 0..n {
            let x = -1.0 + 2.0 * f64::from(i) / f64::from(n - 1);
            let y = -1.0 + 2.0 * f64::from(j) / f64::from(n - 1);
            // Small on the left half, large on the right, with a ramp so that the
            // percentile limits fall inside each half.
            let sd = if x < 0.0 {
                0.01 + 0.001 * (x + 1.0)
            } else {
                1.0 + x
            };
            writeln!(text, "{x},{y},0,0,0,1,0,0,{sd},0").unwrap();
        }
    }
    fs::write(&input, text).unwrap();
    let out = dir.path().join("plane-sd.png");
    run_ok(
        mlscurv()
            .arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(["--field", "k1_sd", "--view", "+z", "--size", "400x400"]),
    );
    let picture = Picture::read(&out);
    let brightness = |xs: std::ops::Range<u32>| {
        let rows = TITLE_BAND + 40..400 - LEGEND_BAND - 40;
        let mut sum = 0.0;
        let mut count = 0.0;
        for y in rows {
            for x in xs.clone() {
                let [r, g, b] = picture.at(x, y);
                sum += f64::from(r) + f64::from(g) + f64::from(b);
                count += 1.0;
            }
        }
        sum / count
    };
    let (left, right) = (brightness(85..180), brightness(220..315));
    assert!(
        left < 250.0 && right > left + 150.0,
        "left {left:.0}, right {right:.0}"
    );
}
