//! (being written)
#[path = "model_support.rs"]
mod support;
