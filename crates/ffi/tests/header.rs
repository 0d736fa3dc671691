//! The checked-in C header is what cbindgen makes of the C entry points today: a stale header
//! fails here (regenerate on purpose with `JAWTRACK_BLESS=1`).

#[test]
fn the_c_header_is_current() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{dir}/cbindgen.toml")).expect("cbindgen.toml");
    let mut made = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads the crate")
        .write(&mut made);
    let path = format!("{dir}/include/jawtrack.h");
    if std::env::var_os("JAWTRACK_BLESS").is_some() {
        std::fs::write(&path, &made).expect("writing the header");
    }
    let stored = std::fs::read(&path).expect("include/jawtrack.h");
    assert!(
        stored == made,
        "include/jawtrack.h is stale: regenerate it with `JAWTRACK_BLESS=1 cargo test -p jawtrack-ffi --test header` and commit it"
    );
}
