//! Criterion benches of one TLED step (element pass + node pass) on a cube of
//! 10^3 hexahedra / 6 x 10^3 tetrahedra, f64 and f32.

use std::sync::Arc;

use carus_fem::{
    BoundaryConditions, ElementKind, Material, MaterialRegion, Mesh, ModelOptions, Precision,
    StepControl, TledModel, TledSolver,
};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

/// n^3 unit hexahedra of edge h, VTK node order (a bench-local generator so
/// the bench does not depend on the validation module).
fn cube(n: usize, h: f64, kind: ElementKind) -> Mesh {
    let id = |i: usize, j: usize, k: usize| ((k * (n + 1) + j) * (n + 1) + i) as u32;
    let mut nodes = Vec::new();
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                nodes.push([i as f64 * h, j as f64 * h, k as f64 * h]);
            }
        }
    }
    let mut conn = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ];
                match kind {
                    ElementKind::H8 => conn.extend_from_slice(&c),
                    ElementKind::T4 => {
                        for t in [
                            [0, 1, 2, 6],
                            [0, 2, 3, 6],
                            [0, 3, 7, 6],
                            [0, 7, 4, 6],
                            [0, 4, 5, 6],
                            [0, 5, 1, 6],
                        ] {
                            conn.extend(t.iter().map(|&a| c[a]));
                        }
                    }
                }
            }
        }
    }
    Mesh::new(kind, nodes, conn)
}

fn bench_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("tled_step");
    for kind in [ElementKind::H8, ElementKind::T4] {
        for precision in [Precision::F64, Precision::F32] {
            let mesh = cube(10, 0.01, kind);
            let options = ModelOptions {
                precision,
                damping_per_s: 5.0,
                ..ModelOptions::default()
            };
            let region = MaterialRegion {
                element_set: None,
                material: Material::neo_hookean(1006.711409, 50_000.0),
                density_kg_m3: 1000.0,
            };
            let model = Arc::new(TledModel::new(&mesh, &[region], &options).expect("valid cube"));
            let mut bc = BoundaryConditions {
                gravity_m_s2: Some([0.0, 0.0, -9.81]),
                ..BoundaryConditions::default()
            };
            let x0: Vec<u32> = (0..mesh.node_count() as u32)
                .filter(|&n| mesh.nodes[n as usize][2] == 0.0)
                .collect();
            bc.fix_nodes(&x0);
            let dt = 0.9 * model.critical_time_step();
            let mut solver =
                TledSolver::new(model, &bc, dt, StepControl::Refuse).expect("stable step");
            group.throughput(Throughput::Elements(mesh.element_count() as u64));
            group.bench_function(format!("{}_{:?}", kind.name(), precision), |b| {
                b.iter(|| solver.step().expect("step"))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
