//! `read_xyz` on arbitrary bytes: no panic, no hang, bounded memory; a successful read
//! survives a write and re-read unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mls_io::{read_xyz, write_xyz_to};

mod common;

const NAME: &str = "fuzz.xyz";

fuzz_target!(|data: &[u8]| {
    match read_xyz(data, NAME) {
        Ok(cloud) => {
            common::check_cloud(&cloud);
            // An empty cloud writes no rows (and the writer wants at least one column).
            if !cloud.is_empty() {
                let mut bytes = Vec::new();
                write_xyz_to(&mut bytes, NAME, &cloud.columns()).unwrap();
                assert_eq!(read_xyz(&bytes[..], NAME).unwrap(), cloud);
            }
        }
        Err(err) => common::check_error(&err, NAME),
    }
});
