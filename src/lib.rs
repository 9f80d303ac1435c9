//! Host package of the workspace-level integration tests (`tests/`) and criterion benchmarks
//! (`benches/`). It has no API of its own.
#![forbid(unsafe_code)]
