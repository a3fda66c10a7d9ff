//! The TOML case file: schema, defaults, validation, `--set` overrides.
