//! `read_xyz` on arbitrary bytes: no panic, no hang, bounded memory; a successful read
//! survives a write and re-read unchanged, unless a column was dropped (a headerless file's
//! columns are named and read by position, which the dropped column shifts).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mls_io::{ReadOptions, ReadOutcome, read_xyz, read_xyz_with, write_xyz_to};

mod common;

const NAME: &str = "fuzz.xyz";

fuzz_target!(|data: &[u8]| {
    match read_xyz_with(data, NAME, &ReadOptions::default()) {
        Ok(ReadOutcome { cloud, notes }) => {
            common::check_cloud(&cloud);
            let dropped = notes.iter().any(|n| n.contains("is not carried"));
            // An empty cloud writes no rows (and the writer wants at least one column).
            if !cloud.is_empty() && !dropped {
                let mut bytes = Vec::new();
                write_xyz_to(&mut bytes, NAME, &cloud.columns()).unwrap();
                assert_eq!(read_xyz(&bytes[..], NAME).unwrap(), cloud);
            }
        }
        Err(err) => common::check_error(&err, NAME),
    }
});
