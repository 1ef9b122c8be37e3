//! `read_csv` on arbitrary bytes: no panic, no hang, bounded memory; a successful read
//! survives a write and re-read unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mls_io::{read_csv, write_csv_to};

mod common;

const NAME: &str = "fuzz.csv";

fuzz_target!(|data: &[u8]| {
    match read_csv(data, NAME) {
        Ok(cloud) => {
            common::check_cloud(&cloud);
            let mut bytes = Vec::new();
            write_csv_to(&mut bytes, NAME, &cloud.columns()).unwrap();
            assert_eq!(read_csv(&bytes[..], NAME).unwrap(), cloud);
        }
        Err(err) => common::check_error(&err, NAME),
    }
});
