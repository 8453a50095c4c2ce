//! Inputs the fuzzer (fuzz/, docs/fuzzing.md) found crashing or hanging `cbr compare`'s image
//! reader, replayed exactly as the `image_input` target reads them: the first byte picks the file
//! name's extension and the layer and channels asked for, the rest is the file. Each must give a
//! clean `Ok` or `Err` (a panic here, or in a decoder thread, fails the test binary).

use std::io::Cursor;
use std::path::Path;

use cbr_metrics::input::read;

/// Each regression file and what reading it must give: `Ok(())`, or an error containing the text.
const EXPECTED: &[(&str, Result<(), &str>)] = &[
    // exr 1.74's B44 decoder subtracts past zero on a corrupt block: with overflow checks (debug
    // builds) a decoder thread panicked and rayon aborted the process.
    ("exr-b44-overflow.bin", Ok(())),
    // A 0.5 kB EXR whose header declares a layer of 1.4 TB: the decoder allocated it up front
    // and the allocation failure aborted the process.
    ("exr-huge-layer.bin", Err("at most 16384 per side")),
    // A tiled EXR whose tile at an offset-table slot of level 0 says it is at level (0, 7):
    // exr's `debug_assert` ("line should have been filtered") panicked in debug builds; release
    // builds write the tile's lines inside the layer.
    ("exr-tile-level-mismatch.bin", Ok(())),
];

fn replay(data: &[u8]) -> Result<(), String> {
    let (&first, bytes) = data.split_first().ok_or("empty input")?;
    let name = ["in.exr", "in.png", "in.jpg", "in.tga"][usize::from(first & 3)];
    let one = ["Z".to_string()];
    let rgb = ["R".to_string(), "G".to_string(), "B".to_string()];
    let (layer, channels): (Option<&str>, Option<&[String]>) = match (first >> 2) & 3 {
        0 => (None, None),
        1 => (Some("depth"), Some(&one)),
        2 => (Some("color"), Some(&rgb)),
        _ => (None, Some(&one)),
    };
    read(Path::new(name), Cursor::new(bytes), layer, channels)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn fuzz_regressions_read_cleanly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("regression folder") {
        let path = entry.expect("entry").path();
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let expected = EXPECTED
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("{name}: add its expected outcome to EXPECTED"))
            .1;
        let got = replay(&std::fs::read(&path).expect("read"));
        match (expected, &got) {
            (Ok(()), Ok(())) => {}
            (Err(want), Err(e)) if e.contains(want) => {}
            _ => panic!("{name}: expected {expected:?}, got {got:?}"),
        }
        seen += 1;
    }
    assert_eq!(seen, EXPECTED.len(), "every listed file is present");
}
