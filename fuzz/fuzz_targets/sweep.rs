//! `sweep.txt`, a 0 byte, `results.csv` → what `sweep-merge` reads, merges and plots (`pelage::robust::sweep_files`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    pelage::robust::sweep_files(data);
});
