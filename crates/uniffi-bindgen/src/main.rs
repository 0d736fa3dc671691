//! `uniffi-bindgen`: generates the Swift (and, for the tests here, Python) bindings of
//! `jawtrack-ffi` from its compiled library: `cargo run -p uniffi-bindgen -- generate
//! --library target/release/libjawtrack_ffi.so --language python --out-dir DIR`.

fn main() {
    uniffi::uniffi_bindgen_main()
}
