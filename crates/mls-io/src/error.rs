//! Typed errors: one enum for reading, one for writing.
//!
//! Every message is a single line that starts with the file name, so a command-line tool can
//! print it as it is. Text taken from the input is quoted with escapes and shortened, so a
//! malformed file cannot break that rule.

use std::io;

/// Why a point cloud could not be read.
///
/// `file` is the path as given (or the display name passed to a stream reader). Line numbers
/// count from 1; byte offsets count from 0 at the start of the file; vertex and element
/// indices count from 0, as PLY face lists do.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened, or reading from it failed.
    #[error("{file}: {error}")]
    Io {
        /// The file.
        file: String,
        /// The operating-system error. Not a `source`: the message already states it, and
        /// error reporters that print the chain would repeat it.
        error: io::Error,
    },
    /// The path names a directory, not a file.
    #[error(
        "{file}: is a directory; expected a point-cloud file (.ply, .xyz, .txt, .pts, .asc, .csv, .las, .laz or .e57)"
    )]
    IsADirectory {
        /// The path.
        file: String,
    },
    /// The file name has no extension, so its format is unknown.
    #[error(
        "{file}: no file extension; expected .ply, .xyz, .txt, .pts, .asc, .csv, .las, .laz or .e57"
    )]
    NoExtension {
        /// The file.
        file: String,
    },
    /// The file name has an extension that names no supported format.
    #[error(
        "{file}: unknown extension \".{extension}\"; expected .ply, .xyz, .txt, .pts, .asc, .csv, .las, .laz or .e57"
    )]
    UnknownExtension {
        /// The file.
        file: String,
        /// The extension, without the dot.
        extension: String,
    },
    /// The PLY header (or the CSV header row) is malformed: bad magic, missing `end_header`,
    /// unknown format, keyword or property type, duplicate property, and the like.
    #[error("{file}: header line {line}: {message}")]
    Header {
        /// The file.
        file: String,
        /// The header line at fault.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// A required coordinate (`x`, `y` or `z`) is not among the PLY vertex properties or the
    /// CSV columns.
    #[error("{file}: line {line}: no \"{field}\" field; x, y and z are required")]
    MissingField {
        /// The file.
        file: String,
        /// The line that declares the fields (the PLY `element vertex` line or the CSV header).
        line: usize,
        /// The missing field.
        field: &'static str,
    },
    /// Some but not all of `nx`, `ny`, `nz` are present.
    #[error("{file}: line {line}: normals need all of nx, ny and nz, but {missing} missing")]
    PartialNormals {
        /// The file.
        file: String,
        /// The line that declares the fields (the PLY `element vertex` line or the CSV header).
        line: usize,
        /// The missing components with a verb, e.g. `"nz is"` or `"ny and nz are"`.
        missing: String,
    },
    /// The first data row of an XYZ/TXT/PTS file has fewer than 3 columns.
    #[error(
        "{file}: line {line}: {found} column(s); expected at least 3 (x y z ...), separated \
         by whitespace, commas or semicolons"
    )]
    UnsupportedColumnCount {
        /// The file.
        file: String,
        /// The first data row.
        line: usize,
        /// Its number of columns.
        found: usize,
    },
    /// An XYZ/TXT/ASC file that begins like an ESRI ASCII grid (`ncols`), a raster.
    #[error(
        "{file}: line {line}: \"ncols\" begins an ESRI ASCII grid, a raster of heights, not a \
         point cloud; convert it to x y z rows first (for example gdal_translate -of XYZ)"
    )]
    RasterGrid {
        /// The file.
        file: String,
        /// The `ncols` line.
        line: usize,
    },
    /// A text file's point-count line (a single integer before the rows) states another
    /// number of rows than follow it: a truncated or concatenated file.
    #[error(
        "{file}: line {line} states {stated} point(s), but {found} row(s) follow it: the file is truncated or holds more than that cloud"
    )]
    CountMismatch {
        /// The file.
        file: String,
        /// The count line.
        line: usize,
        /// The count it states.
        stated: u64,
        /// The rows read.
        found: u64,
    },
    /// The column names given in [`ReadOptions::columns`](crate::ReadOptions::columns)
    /// (`--columns`) are not as many as the columns of the first data row (XYZ) or the
    /// header (CSV).
    #[error("{file}: line {line}: {found} columns, but {by} names {named}")]
    ColumnsMismatch {
        /// The file.
        file: String,
        /// The first data row or the header.
        line: usize,
        /// Its number of columns.
        found: usize,
        /// The names given.
        named: String,
        /// Where they were given: `--columns`, or the file's own `//` line.
        by: String,
    },
    /// Column names were given for a PLY or LAS/LAZ file, whose header names its fields.
    #[error(
        "{file}: --columns applies to text files (.xyz, .txt, .pts, .asc, .csv); a PLY, LAS or E57 \
         header names its fields"
    )]
    ColumnsForPly {
        /// The file.
        file: String,
    },
    /// A row has a different number of columns from the first data row (XYZ) or the header
    /// (CSV).
    #[error("{file}: line {line}: {found} columns, expected {expected}")]
    ColumnCount {
        /// The file.
        file: String,
        /// The row at fault.
        line: usize,
        /// Its number of columns.
        found: usize,
        /// The number every row must have.
        expected: usize,
    },
    /// A value in a text file (ASCII PLY, XYZ, CSV) is missing, not a number, not finite, or
    /// the file ends before the header's element count is reached.
    #[error("{file}: line {line}, {field}: {message}")]
    Ascii {
        /// The file.
        file: String,
        /// The line at fault.
        line: usize,
        /// The field, e.g. `vertex 17 property y` or `column 2 (y)`.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A value in a binary PLY body is invalid: a NaN or infinite coordinate or normal, or a
    /// negative list length.
    #[error("{file}: {message} at byte {offset}, {field}")]
    Binary {
        /// The file.
        file: String,
        /// Where the value starts.
        offset: u64,
        /// The value, e.g. `vertex 17 property y (float32)`.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A binary PLY body ends before the header's element counts are reached.
    #[error("{file}: truncated binary body at byte {offset}: expected {field}")]
    Truncated {
        /// The file.
        file: String,
        /// Where the missing value would start.
        offset: u64,
        /// The value, e.g. `vertex 17 property y (float32)`.
        field: String,
    },
    /// A LAS or LAZ file could not be read: not a LAS file (wrong signature), a header or
    /// VLR the `las` crate refuses (such as an unsupported point format), data that ends
    /// before the header's point count, corrupt compressed data, or a coordinate that is not
    /// finite.
    #[error("{file}: {message}")]
    Las {
        /// The file.
        file: String,
        /// What is wrong, e.g. `not a LAS file: …` or `truncated: …`.
        message: String,
    },
    /// An E57 file the `e57` crate cannot read (not E57, truncated, a checksum or XML error),
    /// with no scans, a scan without Cartesian or spherical coordinates, or a coordinate that
    /// is not finite. The message names the scan and point where it can.
    #[error("{file}: {message}")]
    E57 {
        /// The file.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A file read more than once ([`PointStream`](crate::PointStream)) gave a different
    /// number of points than the first time: it changed meanwhile.
    #[error("{file}: the file changed while it was read: {first} points the first time, {now} now")]
    Changed {
        /// The file.
        file: String,
        /// The points found the first time.
        first: u64,
        /// The points found this time.
        now: u64,
    },
}

/// Why a table could not be written. On any of these the destination file is untouched.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// Creating the temporary file, writing, syncing it or renaming it over the destination
    /// failed (for example, the directory does not exist or is not writable).
    #[error("{file}: {error}")]
    Io {
        /// The destination.
        file: String,
        /// The operating-system error. Not a `source`: the message already states it, and
        /// error reporters that print the chain would repeat it.
        error: io::Error,
    },
    /// The destination path has no file name (such as `/` or `..`).
    #[error("{file}: not a file path")]
    NotAFilePath {
        /// The destination.
        file: String,
    },
    /// The destination has no extension, so the output format is unknown.
    #[error("{file}: no file extension; expected .ply, .csv, .xyz, .txt, .pts, .asc, .las or .laz")]
    NoExtension {
        /// The destination.
        file: String,
    },
    /// The destination's extension names no supported output format.
    #[error(
        "{file}: unknown extension \".{extension}\"; expected .ply, .csv, .xyz, .txt, .pts, .asc, .las or .laz"
    )]
    UnknownExtension {
        /// The destination.
        file: String,
        /// The extension, without the dot.
        extension: String,
    },
    /// No columns were given.
    #[error("{file}: no columns to write")]
    NoColumns {
        /// The destination.
        file: String,
    },
    /// Two columns have different lengths.
    #[error("{file}: column \"{column}\" has {len} rows but column \"{first}\" has {expected}")]
    LengthMismatch {
        /// The destination.
        file: String,
        /// The first column.
        first: String,
        /// Its length, which every column must have.
        expected: usize,
        /// The column at fault.
        column: String,
        /// Its length.
        len: usize,
    },
    /// A table written in chunks ([`write_point_cloud_chunks`](crate::write_point_cloud_chunks))
    /// got another number of rows than it declared (the PLY header holds the count).
    #[error("{file}: {declared} rows declared, but {written} given")]
    RowCount {
        /// The destination.
        file: String,
        /// The rows declared.
        declared: u64,
        /// The rows given.
        written: u64,
    },
    /// A column name would not survive a round trip through PLY or CSV.
    #[error("{file}: invalid column name {name:?}: {reason}")]
    InvalidColumnName {
        /// The destination.
        file: String,
        /// The name at fault.
        name: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// Two columns have the same name.
    #[error("{file}: duplicate column name \"{name}\"")]
    DuplicateColumn {
        /// The destination.
        file: String,
        /// The repeated name.
        name: String,
    },
    /// LAS output needs the columns `x`, `y` and `z` for the point coordinates.
    #[error("{file}: no \"{field}\" column; LAS output needs x, y and z")]
    MissingCoordinate {
        /// The destination.
        file: String,
        /// The missing column.
        field: &'static str,
    },
    /// A coordinate to write as LAS is NaN or infinite: LAS stores coordinates as integer
    /// steps of a grid.
    #[error("{file}: column \"{column}\" row {row} is not finite; LAS coordinates must be")]
    NonFiniteCoordinate {
        /// The destination.
        file: String,
        /// The coordinate column.
        column: String,
        /// The row, from 0.
        row: usize,
    },
    /// A format this crate reads but does not write (E57).
    #[error("{file}: {format} is an input format only; write .ply, .csv, .xyz, .las or .laz")]
    ReadOnlyFormat {
        /// The destination.
        file: String,
        /// The format's name.
        format: &'static str,
    },
    /// The `las` crate refused the header or a point.
    #[error("{file}: LAS: {message}")]
    Las {
        /// The destination.
        file: String,
        /// The crate's message.
        message: String,
    },
}

/// Quotes text taken from the input for an error message: escaped, so the message stays on
/// one line, and shortened, so a runaway token does not swamp it.
pub(crate) fn quoted(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    if text.chars().count() <= MAX_CHARS {
        format!("{text:?}")
    } else {
        let head: String = text.chars().take(MAX_CHARS).collect();
        format!("{head:?}…")
    }
}

#[cfg(test)]
mod tests {
    use super::quoted;

    #[test]
    fn quoting_escapes_and_shortens() {
        assert_eq!(quoted("a\nb"), "\"a\\nb\"");
        let long = "x".repeat(100);
        let q = quoted(&long);
        assert!(q.len() < 50, "{q}");
        assert!(q.ends_with('…'));
    }
}
