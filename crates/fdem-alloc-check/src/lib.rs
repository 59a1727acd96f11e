//! Test-only crate: its test `tests/no_alloc.rs` installs a counting global
//! allocator (an `unsafe` trait, which every other crate of the workspace
//! forbids) and checks DESIGN's rule that a time step allocates nothing
//! except on a topology change. This library is empty.
#![forbid(missing_docs)]
