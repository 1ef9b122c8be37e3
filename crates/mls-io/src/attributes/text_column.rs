//! A column of a text file (XYZ, CSV) read before its type is known: integers until a value
//! is not one, then floats, or dropped at a value that is not a number; finished into an
//! attribute column of the narrowest type that holds it.

use super::AttributeData;

/// A text column on its way to becoming an attribute: integers while every value is one,
/// floats from the first value that is not, and dropped at the first value that is not a
/// number at all.
#[derive(Debug)]
pub(crate) enum TextColumn {
    Integers(Vec<i64>),
    Floats(Vec<f64>),
    /// Not numbers: the line and the text of the first value that is not.
    Dropped(usize, String),
}

impl TextColumn {
    pub(crate) fn new() -> Self {
        Self::Integers(Vec::new())
    }

    pub(crate) fn push(&mut self, line: usize, token: &str) {
        match self {
            Self::Integers(values) => {
                if let Ok(v) = token.parse::<i64>() {
                    values.push(v);
                } else if let Ok(v) = token.parse::<f64>() {
                    // Integers beyond 2^53 round here; a column with a fraction somewhere is
                    // a float column.
                    let mut floats: Vec<f64> = values.iter().map(|&i| i as f64).collect();
                    floats.push(v);
                    *self = Self::Floats(floats);
                } else {
                    *self = Self::Dropped(line, token.to_owned());
                }
            }
            Self::Floats(values) => match token.parse::<f64>() {
                Ok(v) => values.push(v),
                Err(_) => *self = Self::Dropped(line, token.to_owned()),
            },
            Self::Dropped(..) => {}
        }
    }

    /// The values as an attribute column: `int32` if every value is an integer in its range,
    /// `int64` if every value is an integer, else `float64`; or where the column failed.
    pub(crate) fn finish(self) -> Result<AttributeData, (usize, String)> {
        match self {
            Self::Integers(values) => {
                let narrow: Result<Vec<i32>, _> =
                    values.iter().map(|&v| i32::try_from(v)).collect();
                Ok(match narrow {
                    Ok(narrow) => AttributeData::I32(narrow),
                    Err(_) => AttributeData::I64(values),
                })
            }
            Self::Floats(values) => Ok(AttributeData::F64(values)),
            Self::Dropped(line, token) => Err((line, token)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_columns_keep_integers_integer() {
        let column = |tokens: &[&str]| {
            let mut c = TextColumn::new();
            for (i, t) in tokens.iter().enumerate() {
                c.push(i + 1, t);
            }
            c.finish()
        };
        assert_eq!(
            column(&["1", "-2", "255"]),
            Ok(AttributeData::I32(vec![1, -2, 255]))
        );
        assert_eq!(
            column(&["1", "9000000000"]),
            Ok(AttributeData::I64(vec![1, 9_000_000_000]))
        );
        assert_eq!(
            column(&["1", "0.5"]),
            Ok(AttributeData::F64(vec![1.0, 0.5]))
        );
        assert_eq!(column(&["1", "red", "2"]), Err((2, "red".to_owned())));
    }
}
