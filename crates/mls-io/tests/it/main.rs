//! The one integration-test binary of mls-io (one binary keeps link time down).

mod atomic;
mod attributes;
mod cloudcompare;
mod e57;
mod fuzz;
mod las;
mod malformed;
mod ply_fixtures;
mod roundtrip;
mod stream;
mod text;

/// Seeds, named so that a failure can be replayed.
pub mod seeds {
    /// Values for the round-trip tables.
    pub const ROUND_TRIP: u64 = 0x10_0001;
    /// The generated LAS/LAZ table.
    pub const LAS: u64 = 0x10_0002;
}

/// Checks the rules every error message follows (one line, starting with the file name) and
/// that it contains each of `parts`; returns the message.
#[track_caller]
pub fn assert_message(err: &dyn std::error::Error, file: &str, parts: &[&str]) -> String {
    let message = err.to_string();
    assert!(!message.contains('\n'), "not one line: {message:?}");
    assert!(
        message.starts_with(file),
        "does not start with {file:?}: {message:?}"
    );
    for part in parts {
        assert!(message.contains(part), "{message:?} lacks {part:?}");
    }
    message
}

/// Builds a binary PLY body value by value in either byte order.
#[derive(Debug, Default)]
pub struct Body {
    /// The bytes so far.
    pub bytes: Vec<u8>,
    /// Big-endian if set.
    pub big: bool,
}

// One method per PLY type, each appending a value in the body's byte order.
macro_rules! put {
    ($($name:ident: $t:ty),*) => {
        impl Body {
            $(
                /// Appends one value.
                pub fn $name(&mut self, v: $t) -> &mut Self {
                    if self.big {
                        self.bytes.extend_from_slice(&v.to_be_bytes());
                    } else {
                        self.bytes.extend_from_slice(&v.to_le_bytes());
                    }
                    self
                }
            )*
        }
    };
}
put!(i8: i8, u8: u8, i16: i16, u16: u16, i32: i32, u32: u32, f32: f32, f64: f64);

/// A header followed by a body.
pub fn ply(header: &str, body: &[u8]) -> Vec<u8> {
    let mut bytes = header.as_bytes().to_vec();
    bytes.extend_from_slice(body);
    bytes
}
