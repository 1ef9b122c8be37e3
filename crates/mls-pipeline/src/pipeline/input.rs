//! Reading the input: a file or standard input in any format the readers know (recognised
//! from the data when it has no name), the names that stand for standard input and output in
//! messages, and the check that a cloud has enough points for a neighbourhood.

use std::io::{IsTerminal as _, Read as _};
use std::path::Path;

use anyhow::{Result, anyhow, bail};
use mls_core::Point;
use mls_io::{FileFormat, PointCloud, ReadError};

use super::MIN_POINTS;

/// The path that means standard input (as an input) or standard output (as `-o`).
const STDIO: &str = "-";

/// The name of standard input in messages.
pub const STDIN_NAME: &str = "<stdin>";

/// The name of standard output in messages.
pub const STDOUT_NAME: &str = "<stdout>";

pub(crate) fn is_stdio(path: &Path) -> bool {
    path.as_os_str() == STDIO
}

/// How an input is named in messages: its path, or `<stdin>` for `-`.
pub fn input_name(path: &Path) -> String {
    if is_stdio(path) {
        STDIN_NAME.to_owned()
    } else {
        path.display().to_string()
    }
}

/// The name of a format on the command line.
pub fn format_name(format: FileFormat) -> &'static str {
    match format {
        FileFormat::Ply => "ply",
        FileFormat::Xyz => "xyz",
        FileFormat::Csv => "csv",
        FileFormat::Las => "las",
        FileFormat::Laz => "laz",
        FileFormat::E57 => "e57",
    }
}

/// Reads a cloud (see [`read_outcome`]) and prints the reader's notes on stderr, even with
/// `--quiet`: they say how the columns were understood.
pub fn read_any(
    path: &Path,
    format: Option<FileFormat>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<PointCloud> {
    let mls_io::ReadOutcome { cloud, notes } = read_outcome(path, format, columns)?;
    for note in notes {
        eprintln!("mlscurv: note: {note}");
    }
    Ok(cloud)
}

/// Reads a cloud whose columns beyond x, y, z do not matter (eval's queries), without the
/// reader's notes.
pub fn read_quietly(path: &Path, format: Option<FileFormat>) -> Result<PointCloud> {
    Ok(read_outcome(path, format, None)?.cloud)
}

/// Reads a cloud in `format` if given, else in the format its extension names; `-` reads
/// standard input, whose format is otherwise recognised from the data. The column names of
/// `--columns`, if given, name the columns of a text input, from a file or standard input.
pub fn read_outcome(
    path: &Path,
    format: Option<FileFormat>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<mls_io::ReadOutcome> {
    let options = mls_io::ReadOptions {
        columns: columns.cloned(),
    };
    Ok(if is_stdio(path) {
        let stdin = std::io::stdin();
        if stdin.is_terminal() {
            bail!(
                "{STDIN_NAME}: standard input is a terminal; pipe or redirect a point cloud into it"
            );
        }
        let mut bytes = Vec::new();
        stdin
            .lock()
            .read_to_end(&mut bytes)
            .map_err(|e| anyhow!("{STDIN_NAME}: {e}"))?;
        let format = format.unwrap_or_else(|| sniff(&bytes));
        mls_io::read_point_cloud_from_with(&bytes[..], STDIN_NAME, format, &options)?
    } else {
        match format {
            Some(format) => mls_io::read_point_cloud_as_with(path, format, &options)?,
            None => mls_io::read_point_cloud_with(path, &options).map_err(|e| match e {
                ReadError::NoExtension { .. } | ReadError::UnknownExtension { .. } => {
                    anyhow!("{e}; or name the format with --input-format ply|xyz|csv|las|laz|e57")
                }
                e => e.into(),
            })?,
        }
    })
}

/// The format of data without a file name: PLY, LAS/LAZ or E57 by its magic word, else CSV if the first line
/// that is not blank or a `#` comment has a comma or a semicolon and is no row of values (so
/// a header row), else XYZ (whose rows may be comma- or semicolon-separated too).
fn sniff(bytes: &[u8]) -> FileFormat {
    if bytes.starts_with(b"ply") {
        return FileFormat::Ply;
    }
    // LAS and LAZ alike: the reader takes the compression from the header.
    if bytes.starts_with(b"LASF") {
        return FileFormat::Las;
    }
    if bytes.starts_with(b"ASTM-E57") {
        return FileFormat::E57;
    }
    let first = bytes
        .split(|&b| b == b'\n')
        .map(<[u8]>::trim_ascii)
        .find(|line| !line.is_empty() && !line.starts_with(b"#"));
    // Values: the first three fields are numbers, as in a headerless XYZ row.
    let values = |line: &[u8], c: u8| {
        let fields: Vec<&[u8]> = line.split(|&b| b == c).take(3).collect();
        fields.len() == 3
            && fields
                .iter()
                .all(|f| std::str::from_utf8(f).is_ok_and(|f| f.trim().parse::<f64>().is_ok()))
    };
    match first {
        Some(line)
            if (line.contains(&b',') && !values(line, b','))
                || (line.contains(&b';') && !values(line, b';')) =>
        {
            FileFormat::Csv
        }
        _ => FileFormat::Xyz,
    }
}

/// Reads a cloud (see [`read_any`]) and checks it has enough points.
pub fn read(
    path: &Path,
    format: Option<FileFormat>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<PointCloud> {
    let cloud = read_any(path, format, columns)?;
    check_count(cloud.points.len(), &input_name(path))?;
    Ok(cloud)
}

/// Refuses a cloud of fewer than [`MIN_POINTS`] points; `file` names it.
pub fn check_count(n: usize, file: &str) -> Result<()> {
    if n < MIN_POINTS {
        bail!("{file}: {n} point(s); at least {MIN_POINTS} are needed to build a neighbourhood");
    }
    Ok(())
}

pub fn to_points(cloud: &PointCloud) -> Vec<Point> {
    cloud.points.iter().map(|p| Point::from(*p)).collect()
}
