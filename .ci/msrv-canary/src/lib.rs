//! Calls `File::lock` (stable since Rust 1.89) under `rust-version = "1.88"`.

/// Locks `file`.
pub fn lock(file: &std::fs::File) -> std::io::Result<()> {
    file.lock()
}
