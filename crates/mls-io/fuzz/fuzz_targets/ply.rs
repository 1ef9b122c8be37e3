//! `read_ply` on arbitrary bytes: no panic, no hang, bounded memory (libFuzzer's
//! `-rss_limit_mb` and `-malloc_limit_mb` catch a header that makes the reader allocate for the
//! vertex count it claims); a successful read survives a write and re-read in both PLY
//! encodings unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mls_io::{PlyFormat, read_ply, write_ply_to};

mod common;

const NAME: &str = "fuzz.ply";

fuzz_target!(|data: &[u8]| {
    match read_ply(data, NAME) {
        Ok(cloud) => {
            common::check_cloud(&cloud);
            for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
                let mut bytes = Vec::new();
                write_ply_to(&mut bytes, NAME, &cloud.columns(), format).unwrap();
                assert_eq!(read_ply(&bytes[..], NAME).unwrap(), cloud, "{format:?}");
            }
        }
        Err(err) => common::check_error(&err, NAME),
    }
});
