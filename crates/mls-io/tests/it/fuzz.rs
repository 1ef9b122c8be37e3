//! Mutated and random inputs never panic: every reader returns a value or an error.

use mls_io::{PlyFormat, PointCloud, read_csv, read_ply, read_xyz, write_csv_to, write_ply_to};
use proptest::prelude::*;

fn sample() -> PointCloud {
    PointCloud {
        points: vec![[0.0, 1.0, 2.0], [-3.5, 4.25, 1e10], [7.0, 8.0, 9.0]],
        normals: Some(vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        ..PointCloud::default()
    }
}

fn encoded(format: PlyFormat) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_ply_to(&mut bytes, "sample", &sample().columns(), format).unwrap();
    bytes
}

/// Applies `(position, byte)` edits and an optional truncation.
fn mutate(mut bytes: Vec<u8>, edits: &[(usize, u8)], cut: Option<usize>) -> Vec<u8> {
    for &(at, byte) in edits {
        let len = bytes.len();
        if let Some(b) = bytes.get_mut(at % len.max(1)) {
            *b = byte;
        }
    }
    if let Some(cut) = cut {
        bytes.truncate(cut % (bytes.len() + 1));
    }
    bytes
}

proptest! {
    #[test]
    fn mutated_ply_never_panics(
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..8),
        cut in prop::option::of(any::<usize>()),
        ascii in any::<bool>(),
    ) {
        let format = if ascii { PlyFormat::Ascii } else { PlyFormat::BinaryLittleEndian };
        let bytes = mutate(encoded(format), &edits, cut);
        let _ = read_ply(&bytes[..], "fuzz.ply");
    }

    #[test]
    fn mutated_csv_and_xyz_never_panic(
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..8),
        cut in prop::option::of(any::<usize>()),
    ) {
        let mut csv = Vec::new();
        write_csv_to(&mut csv, "sample", &sample().columns()).unwrap();
        let bytes = mutate(csv, &edits, cut);
        let _ = read_csv(&bytes[..], "fuzz.csv");
        let _ = read_xyz(&bytes[..], "fuzz.xyz");
    }

    #[test]
    fn random_headers_never_panic(body in prop::collection::vec(any::<u8>(), 0..256)) {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\n".to_vec();
        bytes.extend_from_slice(&body);
        let _ = read_ply(&bytes[..], "fuzz.ply");
    }
}

/// Header lines that combine into plausible, often inconsistent, headers.
const HEADER_LINES: [&str; 14] = [
    "element vertex 3",
    "element vertex 1000000000000",
    "element face 2",
    "property float x",
    "property double y",
    "property uchar z",
    "property float nx",
    "property int16 ny",
    "property float nz",
    "property list uchar int vertex_indices",
    "property list int8 double l",
    "comment hello",
    "format ascii 1.0",
    "end_header",
];

proptest! {
    #[test]
    fn assembled_headers_never_panic(
        big in any::<bool>(),
        lines in prop::collection::vec(0..HEADER_LINES.len(), 0..14),
        body in prop::collection::vec(any::<u8>(), 0..200),
    ) {
        let format = if big { "binary_big_endian" } else { "binary_little_endian" };
        let mut bytes = format!("ply\nformat {format} 1.0\n").into_bytes();
        for line in lines {
            bytes.extend_from_slice(HEADER_LINES.get(line).copied().unwrap_or("").as_bytes());
            bytes.push(b'\n');
        }
        bytes.extend_from_slice(b"end_header\n");
        bytes.extend_from_slice(&body);
        let _ = read_ply(&bytes[..], "fuzz.ply");
    }
}
