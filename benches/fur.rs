//! The costs issue 5 tracks, each alone:
//! - `bake`: the fur textures of thesis chapter 4.2 (3000 strands × 30 shells × 128², circle
//!   and strand resolution 20) and of its heavy start-up case (10,000 strands, circle 50);
//! - `frame`: one frame of `scenes/thesis-4-2.toml` at 1366×768, baked once outside the loop;
//! - `character`: the walking fox of `scenes/fox.toml` at 1366×768 with 30 shells: posing alone
//!   (skinning and frames on the posed surface, `PreparedScene::mesh_at`) and the whole frame,
//!   so the share posing takes can be read off (the bound: at most 10 %);
//! - `shading`: the fragment stage's terms on their own (strand lighting with its batched
//!   powers, the shell shadow's lookups, a light spot, the burn rule), per fragment.
//!
//! Run: `cargo bench --bench fur` (one group: `cargo bench --bench fur -- bake`).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use pelage::fur::{FurParams, bake_shells, generate_strands};
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use pelage::shading::{self, LightingExponents, SpecularTangents};
use std::hint::black_box;
use std::path::Path;

fn bake(c: &mut Criterion) {
    let mut group = c.benchmark_group("bake");
    group.sample_size(10);
    for (name, strands, circle) in [("thesis-4-2", 3000, 20), ("start-up-16s", 10_000, 50)] {
        let params = FurParams {
            number_of_strands: strands,
            strand_resolution: 20,
            circle_resolution: circle,
            number_of_shells: 30,
            texture_resolution: 128,
            ..FurParams::default()
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                let strands = generate_strands(&params, 1234).expect("strands");
                black_box(bake_shells(&params, &strands).expect("bake"))
            })
        });
    }
    group.finish();
}

fn frame(c: &mut Criterion) {
    let scene = Scene::load(Path::new("scenes/thesis-4-2.toml")).expect("thesis-4-2 scene");
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let mut group = c.benchmark_group("frame");
    group.sample_size(10);
    let fragments = prepared.render(64).expect("frame").stats.fragments_shaded;
    group.throughput(Throughput::Elements(fragments));
    group.bench_function("thesis-4-2", |b| {
        b.iter(|| black_box(prepared.render(64).expect("frame")))
    });
    group.finish();
}

fn character(c: &mut Criterion) {
    let mut scene = Scene::load(Path::new("scenes/fox.toml")).expect("fox scene");
    scene.image.width = 1366;
    scene.image.height = 768;
    scene.fur.number_of_shells = 30;
    scene.time = 0.4;
    let prepared = PreparedScene::new(&scene).expect("prepare");
    let mut group = c.benchmark_group("character");
    group.sample_size(10);
    group.bench_function("fox-posing", |b| {
        b.iter(|| black_box(prepared.mesh_at(black_box(0.4))))
    });
    group.bench_function("fox-frame", |b| {
        b.iter(|| black_box(prepared.render(64).expect("frame")))
    });
    group.finish();
}

fn shading_terms(c: &mut Criterion) {
    // A fixed set of inputs, varied enough that no branch predictor learns one path.
    let inputs: Vec<(Vec3, Vec3, Vec3)> = (0..1024)
        .map(|i| {
            let a = i as f32 * 0.618;
            (
                Vec3::new(a.cos(), a.sin(), 0.3).normalize(),
                Vec3::new(0.4, (a * 1.3).cos(), 0.8).normalize(),
                Vec3::new((a * 0.7).sin(), 0.2, 0.9).normalize(),
            )
        })
        .collect();
    let exponents = LightingExponents {
        banks: shading::BANKS_EXPONENT,
        specular: 80.0,
        dampened: 20.0,
    };
    let mut group = c.benchmark_group("shading");
    group.throughput(Throughput::Elements(inputs.len() as u64));
    for tangents in [
        SpecularTangents::One,
        SpecularTangents::Three(shading::SpecularLobes::Sum),
    ] {
        group.bench_with_input(
            BenchmarkId::new("strand_lighting", format!("{tangents:?}")),
            &tangents,
            |b, &tangents| {
                b.iter(|| {
                    inputs
                        .iter()
                        .map(|&(t, l, e)| {
                            let s = shading::strand_lighting(
                                t,
                                Vec3::Z,
                                l,
                                e,
                                exponents,
                                tangents,
                                0.1,
                            );
                            s.diffuse + s.specular + s.specular_to_dampen
                        })
                        .sum::<f32>()
                })
            },
        );
    }
    group.bench_function("separate_terms_one_tangent", |b| {
        b.iter(|| {
            inputs
                .iter()
                .map(|&(t, l, e)| {
                    shading::kajiya_kay_diffuse(t, l, exponents.banks)
                        + shading::kajiya_kay_specular(t, l, e, exponents.specular)
                        + shading::kajiya_kay_specular(t, l, e, exponents.dampened)
                })
                .sum::<f32>()
        })
    });
    group.bench_function("shell_shadow_6_lookups", |b| {
        b.iter(|| {
            inputs
                .iter()
                .map(|&(t, _, _)| {
                    shading::shell_shadow(
                        |at| {
                            if (at.x * 37.0).fract() > 0.5 {
                                1.0
                            } else {
                                0.0
                            }
                        },
                        Vec2::new(t.x, t.y),
                        Vec2::new(0.01, 0.02),
                        6,
                        shading::ShadowTexel::Opaque,
                    )
                })
                .sum::<f32>()
        })
    });
    group.bench_function("light_spot", |b| {
        b.iter(|| {
            inputs
                .iter()
                .map(|&(n, d, _)| {
                    shading::spot_gradient(shading::light_spot_intensity(n, d, 40.0), 0.7, 0.3)
                })
                .sum::<f32>()
        })
    });
    group.bench_function("burn_rule", |b| {
        b.iter(|| {
            inputs
                .iter()
                .enumerate()
                .map(|(i, &(n, d, _))| {
                    let intensity = shading::light_spot_intensity(n, d, 8.0);
                    shading::burn_rule(intensity, (i % 30) as u32, 29).alpha(1.0)
                })
                .sum::<f32>()
        })
    });
    group.finish();
}

criterion_group!(benches, bake, frame, character, shading_terms);
criterion_main!(benches);
