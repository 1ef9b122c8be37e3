//! `mlscurv render`: a picture of one column of a result file, each point a shaded disc
//! coloured by its value, through the splat renderer of the paper figures (mls-render).
//!
//! Self-contained on purpose: it reads with mls-io and checks its own output, and shares
//! nothing with the computing commands but the argument parser.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result, bail};
use clap::{Args, ValueEnum};
use mls_io::PointCloud;
use mls_render::{Category, Cloud, ColourScale, Legend, Panel, Up, View};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A result of `curvature`, `eval`, `project` or `normals`, or any cloud with the field's
    /// column: .ply, .xyz/.txt/.pts/.asc with named columns, .csv, .las/.laz.
    input: PathBuf,
    /// The picture to write (.png).
    #[arg(short, long)]
    output: PathBuf,
    /// The column to colour by: a curvature on a diverging blue-white-red map centred on 0
    /// (limits ± the 98th percentile of |value|), or the status codes as categories. Points
    /// with a non-zero status or a NaN value are drawn hatched grey.
    #[arg(long, value_enum, default_value_t = Field::Mean)]
    field: Field,
    /// Where the camera looks from: `+x`, `-x`, `+y`, `-y`, `+z`, `-z` (from far out along
    /// that axis), or `AZIMUTH,ELEVATION` in degrees around the --up axis (for z up: azimuth
    /// from +x towards +y, elevation above the xy plane). The default `-60,30` is a
    /// three-quarter view from above.
    #[arg(long, default_value = "-60,30", value_parser = check_view, allow_hyphen_values = true)]
    view: String,
    /// The axis drawn pointing up the picture (scans often have y up).
    #[arg(long, value_enum, default_value_t = UpAxis::Z)]
    up: UpAxis,
    /// Size of the picture in pixels, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "800x700")]
    size: (u32, u32),
    /// Replace the output file even if it is read-only (it keeps its permissions).
    #[arg(long)]
    force: bool,
    /// No summary on stderr.
    #[arg(long, short)]
    quiet: bool,
}

/// A column to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Field {
    /// Mean curvature (k1 + k2)/2.
    Mean,
    /// The larger principal curvature.
    K1,
    /// The smaller principal curvature.
    K2,
    /// Gaussian curvature k1·k2.
    Gauss,
    /// The jet's predicted error of k1 (sequential map from the 2nd to the 98th percentile).
    #[value(name = "k1_sd")]
    K1Sd,
    /// The jet's predicted error of k2.
    #[value(name = "k2_sd")]
    K2Sd,
    /// The status code of each point (0 ok; see `curvature --help`).
    Status,
}

impl Field {
    /// The column's name in result files.
    fn column(self) -> &'static str {
        match self {
            Self::Mean => "mean",
            Self::K1 => "k1",
            Self::K2 => "k2",
            Self::Gauss => "gauss",
            Self::K1Sd => "k1_sd",
            Self::K2Sd => "k2_sd",
            Self::Status => "status",
        }
    }

    /// The colour bar's label: what the value is, and its unit.
    fn label(self) -> &'static str {
        match self {
            Self::Mean => "mean curvature (k1 + k2)/2, 1/(file unit)",
            Self::K1 => "k1, larger principal curvature, 1/(file unit)",
            Self::K2 => "k2, smaller principal curvature, 1/(file unit)",
            Self::Gauss => "Gaussian curvature k1·k2, 1/(file unit)²",
            Self::K1Sd => "predicted error of k1, 1/(file unit)",
            Self::K2Sd => "predicted error of k2, 1/(file unit)",
            Self::Status => "status",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum UpAxis {
    X,
    Y,
    Z,
}

impl From<UpAxis> for Up {
    fn from(axis: UpAxis) -> Self {
        match axis {
            UpAxis::X => Up::X,
            UpAxis::Y => Up::Y,
            UpAxis::Z => Up::Z,
        }
    }
}

/// Checks the syntax of `--view` at parse time, so that a mistake is a usage error; the view
/// itself is built once `--up` is known.
fn check_view(s: &str) -> Result<String, String> {
    View::parse(s, Up::Z).map(|_| s.to_owned())
}

/// The largest picture side: a 16384² picture is 800 MB of pixels already.
const MAX_SIDE: u32 = 16_384;

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let parse = |t: &str| t.trim().parse::<u32>().ok().filter(|&v| v <= MAX_SIDE);
    match s.split_once(['x', 'X', '×']) {
        Some((w, h)) => match (parse(w), parse(h)) {
            (Some(w), Some(h)) if w >= 200 && h >= 200 => Ok((w, h)),
            (Some(_), Some(_)) => Err(format!("`{s}`: at least 200x200 pixels are needed")),
            _ => Err(format!(
                "`{s}`: expected WIDTHxHEIGHT in pixels, each at most {MAX_SIDE}, e.g. 800x700"
            )),
        },
        None => Err(format!("`{s}`: expected WIDTHxHEIGHT, e.g. 800x700")),
    }
}

/// Colours of the status codes 0..=7: Okabe–Ito, distinguishable with the common
/// colour-vision deficiencies; ok is the calm sky blue, so that the failures stand out.
const STATUS_COLOURS: [[u8; 3]; 8] = [
    [0x56, 0xb4, 0xe9],
    [0x00, 0x00, 0x00],
    [0xe6, 0x9f, 0x00],
    [0x00, 0x9e, 0x73],
    [0xf0, 0xe4, 0x42],
    [0xd5, 0x5e, 0x00],
    [0x00, 0x72, 0xb2],
    [0xcc, 0x79, 0xa7],
];

/// Height of the title band mls-render adds above a panel with a figure title.
const TITLE_BAND: u32 = 40;

pub fn render(a: RenderArgs) -> Result<()> {
    check_output(&a.input, &a.output, a.force)?;
    let view = View::parse(&a.view, a.up.into()).map_err(anyhow::Error::msg)?;
    let name = a.input.display().to_string();
    let options = mls_io::ReadOptions {
        columns: comment_names(&a.input),
    };
    let cloud = mls_io::read_point_cloud_normals_as_attributes(&a.input, &options)?;
    let values = column(&cloud, a.field.column(), &name)?;
    let status = match a.field {
        Field::Status => None,
        _ => find(&cloud, "status")
            .map(|_| column(&cloud, "status", &name))
            .transpose()?,
    };
    // A value only where the status says the point is ok.
    let values: Vec<f64> = match &status {
        Some(status) => values
            .iter()
            .zip(status)
            .map(|(&v, &s)| if s == 0.0 { v } else { f64::NAN })
            .collect(),
        None => values,
    };
    let normals = normals(&cloud);
    let without = values.iter().filter(|v| !v.is_finite()).count();
    let (legend, range) = match a.field {
        Field::Status => (
            Legend::Categories(status_categories(&values)),
            String::new(),
        ),
        Field::K1Sd | Field::K2Sd => {
            let scale = ColourScale::robust_sequential(&values, a.field.label());
            let range = format!(", colours {:.3e} to {:.3e}", scale.min, scale.max);
            (Legend::Bar(scale), range)
        }
        field => {
            let scale = ColourScale::robust_symmetric(&values, field.label());
            let range = format!(", colours ±{:.3e}", scale.max);
            (Legend::Bar(scale), range)
        }
    };
    let file_name = a
        .input
        .file_name()
        .map_or_else(|| name.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!(
        "{file_name}: {}, {} points",
        a.field.column(),
        cloud.points.len()
    );
    let panel = Panel {
        title: String::new(),
        values,
        legend,
    };
    let (width, height) = a.size;
    let image = mls_render::render(
        &title,
        Cloud {
            points: &cloud.points,
            normals: normals.as_deref(),
        },
        &[panel],
        view,
        (width, height - TITLE_BAND),
        1,
    )
    .with_context(|| format!("cannot draw {}", a.output.display()))?;
    image.write_png(&a.output)?;
    if !a.quiet {
        eprintln!(
            "mlscurv: wrote {} ({width}×{height}): {} of {} points, {without} without a value{range}",
            a.output.display(),
            a.field.column(),
            cloud.points.len(),
        );
    }
    Ok(())
}

/// The column names of an XYZ file as the writers give them, in a first line `# x y z ...`,
/// when they are as many as the columns of the next line; None for any other file.
fn comment_names(path: &Path) -> Option<mls_io::ColumnNames> {
    use std::io::BufRead as _;
    if mls_io::FileFormat::from_path(path) != Some(mls_io::FileFormat::Xyz) {
        return None;
    }
    let file = std::fs::File::open(path).ok()?;
    let mut lines = std::io::BufReader::new(file).lines();
    let first = lines.next()?.ok()?;
    let names: Vec<&str> = first.strip_prefix('#')?.split_whitespace().collect();
    let row = lines.next()?.ok()?;
    if names.len() < 3 || row.split_whitespace().count() != names.len() {
        return None;
    }
    mls_io::ColumnNames::parse(&names.join(",")).ok()
}

/// The attribute named `name`, if the cloud has one.
fn find<'a>(cloud: &'a PointCloud, name: &str) -> Option<&'a mls_io::Attribute> {
    cloud.attributes.iter().find(|a| a.name == name)
}

/// The values of column `name` as numbers, or an error naming the file and the columns it has.
fn column(cloud: &PointCloud, name: &str, file: &str) -> Result<Vec<f64>> {
    let Some(attribute) = find(cloud, name) else {
        let mut names = vec!["x", "y", "z"];
        if cloud.normals.is_some() {
            names.extend(["nx", "ny", "nz"]);
        }
        names.extend(cloud.attributes.iter().map(|a| a.name.as_str()));
        bail!(
            "{file} has no column `{name}`; it has {} (is it a result of `mlscurv curvature`?)",
            names.join(", ")
        );
    };
    Ok((0..cloud.points.len())
        .map(|i| attribute.data.f64_at(i).unwrap_or(f64::NAN))
        .collect())
}

/// The normals for shading: the file's nx, ny, nz (NaN where a point failed, which the
/// renderer draws unshaded), or none.
fn normals(cloud: &PointCloud) -> Option<Vec<[f64; 3]>> {
    if let Some(normals) = &cloud.normals {
        return Some(normals.clone());
    }
    let [nx, ny, nz] = ["nx", "ny", "nz"].map(|n| find(cloud, n));
    let (nx, ny, nz) = (nx?, ny?, nz?);
    Some(
        (0..cloud.points.len())
            .map(|i| [nx, ny, nz].map(|a| a.data.f64_at(i).unwrap_or(f64::NAN)))
            .collect(),
    )
}

/// One category per status code present, labelled with its name and count; codes without a
/// name are left to the renderer's grey "no value".
fn status_categories(codes: &[f64]) -> Vec<Category> {
    let mut counts = [0usize; STATUS_COLOURS.len()];
    for &c in codes {
        if c >= 0.0 && c < counts.len() as f64 && c.fract() == 0.0 {
            counts[c as usize] += 1;
        }
    }
    counts
        .iter()
        .enumerate()
        .filter(|&(_, &n)| n > 0)
        .map(|(code, &n)| {
            let name = match code {
                0 => "ok",
                _ => mls_core::PointStatus::ALL
                    .iter()
                    .find(|s| usize::from(s.code()) == code)
                    .map_or("?", |s| s.name()),
            };
            Category {
                value: code as f64,
                label: format!("{code} {name}: {n}"),
                colour: STATUS_COLOURS[code],
            }
        })
        .collect()
}

/// Checks the output before the input is read: a `.png` name, not the input, not a directory,
/// in an existing directory, and not read-only unless `force` (as the other commands do).
fn check_output(input: &Path, output: &Path, force: bool) -> Result<()> {
    let name = output.display();
    let is_png = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        bail!("{name}: the picture is written as PNG; name it .png");
    }
    if mls_io::same_file(input, output) {
        bail!("{name}: output path is the input file; refusing to overwrite it");
    }
    let existing = std::fs::metadata(output).ok();
    if existing.as_ref().is_some_and(std::fs::Metadata::is_dir) {
        bail!("{name}: is a directory; expected an output file name");
    }
    mls_pipeline::output::check_replaceable(output, existing.as_ref(), force)
}
