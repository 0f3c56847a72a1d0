//! Image bytes → bitmap load. A decompression bomb (a PNG declaring 100,000 ×
//! 100,000 pixels) must be refused by its header, before decoding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("p3dp-fuzz-image-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("map.png");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    // the folder is the project the image is read in
    let reads = p3dp::base::input::Reads::default();
    reads.allow(&dir);
    if let Ok(b) = p3dp::recipe::load_bitmap(&file, "map.png", &reads) {
        assert!(b.width as u64 * b.height as u64 <= p3dp::base::input::MAX_IMAGE_PIXELS);
    }
});
