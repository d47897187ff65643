//! Scenes: TOML files parsed into a typed, range-checked scene.
