//! The host's C runtime start files call `__libc_start_main`; link the C
//! library for that alone (it is the platform's loader glue, not Rust's `std`).
fn main() {
    println!("cargo:rustc-link-arg-bins=-lc");
}
