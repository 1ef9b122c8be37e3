//! Naming the columns of a text file: the `--columns` description and the reading options.

use std::fmt;
use std::str::FromStr;

use crate::SLOT_NAMES;

/// Largest `|length − 1|` of a unit vector in columns 4–6 of a headerless text file: they are
/// read as normals only when every row is within it (or is `0 0 0`, a missing normal).
///
/// 10⁻³ accepts normals written with three decimals or more (rounding each component by
/// 5·10⁻⁴ moves the length by at most 8.7·10⁻⁴) and rejects colours: an RGB triple is a unit
/// vector only for pure primaries (`1 0 0` …), and never on every row of a real scan.
pub const UNIT_TOLERANCE: f64 = 1e-3;

/// The names of the columns of a text file, in order, as given by a `--columns` description
/// such as `x,y,z,nx,ny,nz,intensity`.
///
/// Names are case-insensitive. `x`, `y`, `z` (required) and `nx`, `ny`, `nz` (all three or
/// none; `normal_x` … as PCL writes them are read as these) are the geometry; any other name
/// (`intensity`, `r`, `g`, `b` …) names an attribute, carried to the output under that name,
/// and `_` marks a column that is skipped without being parsed. Each name is letters, digits and `_`, and every name but `_` appears at most
/// once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnNames(Vec<String>);

impl ColumnNames {
    /// Parses a comma-separated description. The error is a sentence for the user.
    pub fn parse(description: &str) -> Result<Self, String> {
        let names: Vec<String> = description
            .split(',')
            .map(|n| crate::slot_alias(&n.trim().to_ascii_lowercase()).to_owned())
            .collect();
        for (i, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(format!("column {} has no name in `{description}`", i + 1));
            }
            if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(format!(
                    "column {} name `{name}`: use letters, digits and `_` only",
                    i + 1
                ));
            }
        }
        Self::checked(names, description)
    }

    /// The names of a file's own header (a `//` line or a first row of names, as split by
    /// the file's separator), which may be any text: CloudCompare writes its scalar fields'
    /// names, `Mean curvature (0.4)`, with spaces and parentheses. `x y z nx ny nz` (and
    /// PCL's `normal_x` …) are matched case-insensitively; every other name keeps its case,
    /// each character other than an ASCII letter, digit, `_`, `-` or `.` becoming `_`
    /// (`Mean_curvature__0.4_`, whether CloudCompare wrote the spaces as spaces or as `_`), a
    /// repeated one getting `_2`, `_3` …, and an empty one (or one of only `_`) being `colN`
    /// for column `N`. The error is a sentence for the user.
    pub(crate) fn from_header(fields: &[&str]) -> Result<Self, String> {
        let mut taken = std::collections::HashSet::new();
        let names = fields
            .iter()
            .enumerate()
            .map(|(i, field)| {
                let field = field.trim();
                let slot = crate::slot_alias(&field.to_ascii_lowercase()).to_owned();
                if SLOT_NAMES.contains(&slot.as_str()) {
                    return slot;
                }
                let fallback = format!("col{}", i + 1);
                let name = crate::attributes::usable_name(field, &fallback, &mut taken);
                if name.chars().all(|c| c == '_') {
                    taken.remove(&name);
                    crate::attributes::usable_name(&fallback, &fallback, &mut taken)
                } else {
                    name
                }
            })
            .collect();
        Self::checked(names, &fields.join(","))
    }

    /// Checks names for a geometry that can be read: `x`, `y`, `z` present, once each, and
    /// all of `nx`, `ny`, `nz` or none; no attribute named twice.
    fn checked(names: Vec<String>, description: &str) -> Result<Self, String> {
        for (i, name) in names.iter().enumerate() {
            if name != "_" && names[..i].contains(name) {
                return Err(format!("column `{name}` named twice in `{description}`"));
            }
        }
        for required in ["x", "y", "z"] {
            if !names.iter().any(|n| n == required) {
                return Err(format!(
                    "`{description}` has no `{required}`; x, y and z are required"
                ));
            }
        }
        let normals = ["nx", "ny", "nz"]
            .iter()
            .filter(|n| names.iter().any(|m| m == *n))
            .count();
        if normals != 0 && normals != 3 {
            return Err(format!(
                "`{description}` names some of nx, ny, nz; give all three or none"
            ));
        }
        Ok(Self(names))
    }

    /// The names, in column order: lowercase from a description; from a file's header the
    /// geometry's lowercase and the others as the header has them, made writable.
    pub fn names(&self) -> &[String] {
        &self.0
    }

    /// The number of columns described.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether no column is described (never true for a parsed description).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether `nx`, `ny`, `nz` are among the names.
    pub fn has_normals(&self) -> bool {
        self.0.iter().any(|n| n == "nx")
    }

    /// For each column, the slot of [`SLOT_NAMES`] it fills, if any.
    pub(crate) fn slots(&self) -> Vec<Option<usize>> {
        self.0
            .iter()
            .map(|n| SLOT_NAMES.iter().position(|s| s == n))
            .collect()
    }
}

impl FromStr for ColumnNames {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::parse(s)
    }
}

impl fmt::Display for ColumnNames {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0.join(","))
    }
}

/// How to read a file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Names for the columns of a text file (`.xyz`, `.txt`, `.pts`, `.asc`, `.csv`), replacing the
    /// column rule of headerless files and the header row's names of CSV (the header row is
    /// still skipped). `None` reads by the file's own rule. Not for PLY, whose header names
    /// its properties.
    pub columns: Option<ColumnNames>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptions_parse_and_are_checked() {
        let c = ColumnNames::parse(" X,y ,Z,nx,ny,nz,Intensity,_").unwrap();
        assert_eq!(
            c.names(),
            ["x", "y", "z", "nx", "ny", "nz", "intensity", "_"]
        );
        assert_eq!(
            c.slots(),
            [
                Some(0),
                Some(1),
                Some(2),
                Some(3),
                Some(4),
                Some(5),
                None,
                None
            ]
        );
        assert!(c.has_normals());
        assert_eq!(c.to_string(), "x,y,z,nx,ny,nz,intensity,_");
        assert!(!ColumnNames::parse("x,y,z,r,g,b").unwrap().has_normals());
        for (bad, why) in [
            ("x,y", "no `z`"),
            ("x,y,z,nx,ny", "some of nx"),
            ("x,y,z,x", "named twice"),
            ("x,,y,z", "column 2 has no name"),
            ("x,y,z,r g", "letters, digits"),
        ] {
            let err = ColumnNames::parse(bad).unwrap_err();
            assert!(err.contains(why), "{bad}: {err}");
        }
        // Skipped columns may repeat; attributes may not.
        assert!(ColumnNames::parse("x,y,z,_,_").is_ok());
        let err = ColumnNames::parse("x,y,z,r,r").unwrap_err();
        assert!(err.contains("`r` named twice"), "{err}");
    }
}
