//! `pelage completions SHELL`: a completion script on standard output that the shell accepts
//! and that knows every subcommand; an unknown shell is bad input (exit 2). Also the crate's
//! licence: the files the `license` field of Cargo.toml names are there.

mod common;
use common::pelage;

const SUBCOMMANDS: [&str; 9] = [
    "render",
    "bench",
    "sweep",
    "sweep-merge",
    "compare",
    "export",
    "view",
    "diagram",
    "completions",
];

fn script(shell: &str) -> String {
    let o = pelage(&["completions", shell]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{shell}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).expect("UTF-8 script")
}

#[test]
fn bash_completion_is_valid_bash_and_names_every_subcommand() {
    let text = script("bash");
    assert!(text.contains("_pelage()"), "{text}");
    for sub in SUBCOMMANDS {
        assert!(text.contains(sub), "bash completion lacks {sub}");
    }
    // Flags of a subcommand complete too.
    assert!(text.contains("--tolerance") && text.contains("--frames"));
    // bash parses it (-n: read, do not run), when bash is here (it is on every CI machine).
    let dir = common::scratch("completions");
    let file = dir.join("pelage.bash");
    std::fs::write(&file, &text).expect("write");
    if let Ok(o) = std::process::Command::new("bash")
        .arg("-n")
        .arg(&file)
        .output()
    {
        assert!(
            o.status.success(),
            "bash -n: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn zsh_fish_elvish_and_powershell_scripts_are_written() {
    assert!(script("zsh").starts_with("#compdef pelage"));
    let fish = script("fish");
    assert!(fish.contains("complete -c pelage"), "{fish}");
    assert!(fish.contains("sweep-merge"), "{fish}");
    assert!(script("elvish").contains("pelage"));
    assert!(script("powershell").contains("Register-ArgumentCompleter"));
}

#[test]
fn an_unknown_shell_is_bad_input() {
    let o = pelage(&["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("tcsh"), "{err}");
}

#[test]
fn the_licence_files_named_by_cargo_toml_are_there() {
    let root = env!("CARGO_MANIFEST_DIR");
    let manifest = std::fs::read_to_string(format!("{root}/Cargo.toml")).expect("Cargo.toml");
    assert!(manifest.contains("license = \"MIT OR Apache-2.0\""));
    assert!(manifest.contains("rust-version = "));
    let mit = std::fs::read_to_string(format!("{root}/LICENSE-MIT")).expect("LICENSE-MIT");
    assert!(mit.contains("Permission is hereby granted, free of charge"));
    let apache = std::fs::read_to_string(format!("{root}/LICENSE-APACHE")).expect("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0"));
}
