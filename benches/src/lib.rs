//! Benchmarks for Hearth (criterion); see benches/.
