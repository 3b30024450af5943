//! Key reference (docs/configuration.md).
