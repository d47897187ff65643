//! `fur.wgsl` in every GPU language (feature `gpu`, `pelage::gpu::translate`): every output is
//! checked by its field's validator where it is installed (`glslangValidator` from Debian's
//! glslang-tools for GLSL 4.50 and ES 3.00, `spirv-val` from spirv-tools for SPIR-V), HLSL and
//! MSL by naga's validator on the module they are written from; the bindings written down must
//! name every resource of the shader with the slot the code uses, and the uniform layouts must
//! be the ones the GPU backend uploads.
//!
//! With `PELAGE_REQUIRE_VALIDATORS=1` (set by `.ci/run`) a missing validator fails the test
//! instead of skipping it.
#![cfg(feature = "gpu")]

mod common;

use pelage::gpu::SHADER_SOURCE;
use pelage::gpu::translate::{self, LANGUAGES, ResourceKind};
use std::path::{Path, PathBuf};
use std::process::Command;

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("test folder");
    dir
}

/// Writes the translation under `dir` and returns it.
fn written(dir: &Path) -> Vec<translate::ShaderFile> {
    let files = translate::translate_all().unwrap_or_else(|e| panic!("{e}"));
    for f in &files {
        let path = dir.join(&f.path);
        std::fs::create_dir_all(path.parent().expect("parent")).expect("folder");
        std::fs::write(&path, &f.bytes).expect("write");
    }
    files
}

/// Whether `tool` runs; panics when it does not and validators are required.
fn have(tool: &str, version_flag: &str) -> bool {
    let found = Command::new(tool)
        .arg(version_flag)
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var("PELAGE_REQUIRE_VALIDATORS").as_deref() != Ok("1"),
            "{tool} is required (PELAGE_REQUIRE_VALIDATORS=1) but does not run: apt-get install glslang-tools spirv-tools"
        );
        eprintln!(
            "SKIPPED: {} needs {tool} (run .ci/setup)",
            std::thread::current().name().unwrap_or("a test")
        );
    }
    found
}

fn run(tool: &str, args: &[&str], file: &Path) -> Result<(), String> {
    let out = Command::new(tool)
        .args(args)
        .arg(file)
        .output()
        .map_err(|e| format!("{tool}: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{tool} rejects {}:\n{}{}",
            file.display(),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ))
    }
}

#[test]
fn every_language_has_its_code_and_bindings() {
    let files = translate::translate_all().unwrap_or_else(|e| panic!("{e}"));
    let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
    for language in LANGUAGES {
        for name in ["bindings.md", "bindings.json"] {
            let path = format!("{language}/{name}");
            assert!(paths.contains(&path.as_str()), "{path} missing: {paths:?}");
        }
    }
    for ep in translate::ENTRY_POINTS {
        for language in ["glsl-450", "glsl-es-300"] {
            let ext = if ep.starts_with("vs_") {
                "vert"
            } else {
                "frag"
            };
            let path = format!("{language}/{ep}.{ext}");
            assert!(paths.contains(&path.as_str()), "{path} missing");
        }
    }
    // One file holds every entry point in HLSL and MSL, under its WGSL name.
    for path in ["hlsl/fur.hlsl", "msl/fur.metal"] {
        let text = files
            .iter()
            .find(|f| f.path == path)
            .map(|f| String::from_utf8_lossy(&f.bytes).into_owned())
            .unwrap_or_else(|| panic!("{path} missing"));
        for ep in translate::ENTRY_POINTS {
            assert!(text.contains(ep), "{path} lacks entry point {ep}");
        }
    }
    // The same bytes every time (naga's reflection maps are hash maps: nothing may leak their
    // order).
    let again = translate::translate_all().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(files.len(), again.len());
    for (a, b) in files.iter().zip(&again) {
        assert_eq!(a.path, b.path);
        assert!(a.bytes == b.bytes, "{} differs between two runs", a.path);
    }
}

#[test]
fn bindings_name_every_resource_with_the_slot_the_code_uses() {
    let dir = out_dir("shaders-bindings");
    written(&dir);
    let (module, _) = translate::parse(SHADER_SOURCE).unwrap_or_else(|e| panic!("{e}"));
    let bound = module
        .global_variables
        .iter()
        .filter(|(_, g)| g.binding.is_some())
        .count();
    assert_eq!(bound, 13, "fur.wgsl's resources changed: update this test");
    let scene = common::scene("torus", 16, 16);
    let prepared = pelage::render::PreparedScene::new(&scene).expect("prepare");
    let uploaded = pelage::gpu::frame_uniforms(&prepared, scene.time).len();
    for language in LANGUAGES {
        let text = std::fs::read_to_string(dir.join(language).join("bindings.json")).expect("json");
        let json: serde_json::Value = serde_json::from_str(&text).expect("bindings.json parses");
        let resources = json["resources"].as_array().expect("resources");
        assert_eq!(resources.len(), bound, "{language}");
        let md = std::fs::read_to_string(dir.join(language).join("bindings.md")).expect("md");
        for r in resources {
            let name = r["name"].as_str().expect("name");
            assert!(
                md.contains(&format!("`{name}`")),
                "{language}/bindings.md lacks {name}"
            );
        }
        let structs = json["structs"].as_array().expect("structs");
        let frame = structs
            .iter()
            .find(|s| s["name"] == "FrameUniforms")
            .expect("FrameUniforms");
        assert_eq!(
            frame["size"].as_u64(),
            Some(uploaded as u64),
            "{language}: FrameUniforms size against what the backend uploads"
        );
        let layer = structs
            .iter()
            .find(|s| s["name"] == "LayerUniforms")
            .expect("LayerUniforms");
        assert_eq!(
            layer["size"].as_u64(),
            Some(32),
            "{language}: LayerUniforms"
        );
        // Offsets strictly increase and every member fits.
        for s in structs {
            let mut end = 0;
            for m in s["members"].as_array().expect("members") {
                let offset = m["offset"].as_u64().expect("offset");
                assert!(offset >= end, "{language}: {} overlaps", m["name"]);
                end = offset + m["size"].as_u64().expect("size");
            }
            assert!(end <= s["size"].as_u64().expect("size"));
        }
    }
    // The slots written down are the slots in the code.
    let table = translate::resources(&module);
    let hlsl = std::fs::read_to_string(dir.join("hlsl/fur.hlsl")).expect("hlsl");
    let metal = std::fs::read_to_string(dir.join("msl/fur.metal")).expect("msl");
    for r in &table {
        if let Some(register) = &r.hlsl_register {
            let decl = format!(" {} : register({register})", r.name);
            assert!(hlsl.contains(&decl), "fur.hlsl lacks `{decl}`");
        }
        let decl = format!("{} [[{}]]", r.name, r.msl_slot);
        assert!(metal.contains(&decl), "fur.metal lacks `{decl}`");
    }
    // GLSL 4.50: every declaration `layout(… binding = N) … _group_G_binding_B_` has the N the
    // table gives (G, B), and every resource but the sampler is declared somewhere.
    let mut declared = std::collections::BTreeSet::new();
    for entry in std::fs::read_dir(dir.join("glsl-450")).expect("glsl-450") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "json" || e == "md") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("glsl");
        for line in text.lines().filter(|l| l.starts_with("layout(")) {
            let Some(n) = line
                .split("binding = ")
                .nth(1)
                .and_then(|rest| rest.split(')').next())
            else {
                continue;
            };
            let n: u32 = n.parse().expect("binding number");
            let r = table
                .iter()
                .find(|r| line.contains(&format!("_group_{}_binding_{}_", r.group, r.binding)))
                .unwrap_or_else(|| panic!("{}: `{line}` names no resource", path.display()));
            assert_eq!(r.glsl_binding, Some(n), "{}: `{line}`", path.display());
            declared.insert(r.name.clone());
        }
    }
    for r in table.iter().filter(|r| r.kind != ResourceKind::Sampler) {
        assert!(
            declared.contains(&r.name),
            "{} is declared in no GLSL file",
            r.name
        );
    }
}

#[test]
fn glsl_passes_glslang() {
    if !have("glslangValidator", "--version") {
        return;
    }
    let dir = out_dir("shaders-glsl");
    let files = written(&dir);
    let mut checked = 0;
    let mut failures = Vec::new();
    for f in files
        .iter()
        .filter(|f| f.path.ends_with(".vert") || f.path.ends_with(".frag"))
    {
        checked += 1;
        if let Err(e) = run("glslangValidator", &[], &dir.join(&f.path)) {
            failures.push(e);
        }
    }
    assert_eq!(
        checked, 14,
        "7 entry points (two of them skinned) × 2 GLSL versions"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The check can fail: a shader with a type error is rejected.
    let broken = dir.join("broken.frag");
    std::fs::write(
        &broken,
        "#version 450\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec3(1.0); }\n",
    )
    .expect("write");
    assert!(run("glslangValidator", &[], &broken).is_err());
}

#[test]
fn spirv_passes_spirv_val() {
    if !have("spirv-val", "--version") {
        return;
    }
    let dir = out_dir("shaders-spirv");
    written(&dir);
    let spv = dir.join("spirv/fur.spv");
    run("spirv-val", &["--target-env", "vulkan1.0"], &spv).unwrap_or_else(|e| panic!("{e}"));
    // The check can fail: the same module with its bound (word 3) cut below the ids it uses.
    let mut bytes = std::fs::read(&spv).expect("spv");
    bytes[12..16].copy_from_slice(&2u32.to_le_bytes());
    let broken = dir.join("broken.spv");
    std::fs::write(&broken, &bytes).expect("write");
    assert!(run("spirv-val", &["--target-env", "vulkan1.0"], &broken).is_err());
}

#[test]
fn every_source_passes_nagas_validator() {
    // HLSL and MSL have no validator on Debian: they are written from modules naga validated
    // with every check on (translate::parse), the WGSL and the ES 3.00 variant.
    translate::parse(SHADER_SOURCE).unwrap_or_else(|e| panic!("{e}"));
    let variant = translate::es300_source().unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !variant.contains("var<storage"),
        "the ES 3.00 variant has no storage buffers"
    );
    assert!(!variant.contains("textureNumLevels("));
    translate::parse(&variant).unwrap_or_else(|e| panic!("{e}"));
    // The validator can fail: a term with the wrong type is refused.
    let broken = SHADER_SOURCE.replacen(
        "fn ",
        "fn broken() -> f32 { return vec2<f32>(0.0); }\nfn ",
        1,
    );
    assert!(translate::parse(&broken).is_err());
}

#[test]
fn pelage_export_writes_the_shaders_and_replaces_its_own_folder() {
    let dir = out_dir("shaders-export");
    let out = dir.join("export");
    for run in 0..2 {
        let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
            .args(["export", "--width", "32", "--height", "24", "-o"])
            .arg(&out)
            .output()
            .expect("pelage runs");
        assert!(
            o.status.success(),
            "run {run}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    for language in LANGUAGES {
        assert!(
            out.join("shaders")
                .join(language)
                .join("bindings.md")
                .is_file()
        );
    }
    assert_eq!(
        std::fs::read_to_string(out.join("shaders/fur.wgsl")).expect("fur.wgsl"),
        SHADER_SOURCE
    );
}
