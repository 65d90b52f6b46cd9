//! The GPU backend against the CPU backend on lavapipe or any GPU
//! (VALIDATION.md V5 and the coupling hooks). CI installs lavapipe; without
//! any Vulkan adapter these tests fail and say how to get one.
#![cfg(feature = "gpu")]

use std::sync::Arc;

use carus_fem::generate::{box_h8, box_t4};
use carus_fem::gpu::{
    open_solver, AdapterChoice, Backend, BackendSolver, GpuDevice, GpuError, GpuOptions, GpuSolver,
};
use carus_fem::validation::v5;
use carus_fem::validation::CaseSize;
use carus_fem::{
    BoundaryConditions, FemError, FixedDofs, ImposedDisplacement, LoadShape, Material,
    MaterialRegion, Mesh, ModelOptions, MooneyRivlin, NodalForce, Precision, StepControl,
    SurfacePressure, TetFormulation, TledModel, TledSolver,
};

const EDGE_M: f64 = 0.1;

fn device() -> GpuDevice {
    GpuDevice::headless(AdapterChoice::BestAvailable).unwrap_or_else(|e| {
        panic!("the GPU tests need a Vulkan adapter (CI installs lavapipe): {e}")
    })
}

fn model(mesh: &Mesh, tet_formulation: TetFormulation, precision: Precision) -> Arc<TledModel> {
    model_of(
        mesh,
        Material::neo_hookean(1006.711409, 50_000.0),
        tet_formulation,
        precision,
    )
}

fn model_of(
    mesh: &Mesh,
    material: Material,
    tet_formulation: TetFormulation,
    precision: Precision,
) -> Arc<TledModel> {
    let region = MaterialRegion {
        element_set: None,
        material,
        density_kg_m3: 1000.0,
    };
    let options = ModelOptions {
        tet_formulation,
        hourglass_coefficient: 0.075,
        damping_per_s: 5.0,
        precision,
        ..ModelOptions::default()
    };
    Arc::new(TledModel::new(mesh, &[region], &options).unwrap())
}

fn max_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

fn largest(a: &[[f64; 3]]) -> f64 {
    a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[test]
fn v5_small_cubes_agree_with_the_cpu_backend() {
    let report = v5::run_on(&device(), CaseSize::Small).unwrap();
    for c in &report.cases {
        eprintln!(
            "V5 {:?} n={} steps={}: max |u| {:.3e} m, GPU-CPU f64 {:.3e} m, GPU-CPU f32 {:.3e} m (tolerance {:.1e} m) on {}",
            c.element, c.n, c.steps, c.max_displacement_m, c.max_difference_cpu_f64_m, c.max_difference_cpu_f32_m, report.tolerance_m, report.adapter
        );
        // The loaded face moved: a comparison of two resting cubes would prove nothing.
        assert!(c.max_displacement_m > 0.01, "{c:?}");
        assert!(c.passed, "{c:?}");
        for i in 0..3 {
            assert!(
                (c.reaction_gpu_n[i] - c.reaction_cpu_n[i]).abs()
                    < 1e-3 * c.reaction_cpu_n[0].abs(),
                "{c:?}"
            );
        }
    }
    assert!(report.passed);
}

/// Every kind of load at once: fixed face, a smooth imposed displacement,
/// ramped nodal forces, follower pressure and gravity (neo-Hookean H8,
/// Mooney-Rivlin T4ANP).
fn all_loads(mesh: &Mesh) -> BoundaryConditions {
    BoundaryConditions {
        fixed: vec![FixedDofs {
            nodes: mesh.node_sets["x0"].clone(),
            components: [true; 3],
        }],
        displacements: vec![ImposedDisplacement {
            nodes: mesh.node_sets["x1"].clone(),
            components: [Some(0.01), None, Some(-0.005)],
            shape: LoadShape::Smooth345 { duration_s: 0.3 },
        }],
        forces: vec![NodalForce {
            nodes: mesh.node_sets["y1"].clone(),
            force_n: [0.0, 0.02, 0.01],
            shape: LoadShape::Ramp { duration_s: 0.2 },
        }],
        pressures: vec![SurfacePressure {
            triangles: mesh.surfaces["z1"].clone(),
            pressure_pa: 150.0,
            shape: LoadShape::RampHold { ramp_s: 0.25 },
        }],
        gravity_m_s2: Some([0.0, 0.0, -9.81]),
    }
}

#[test]
fn every_load_kind_agrees_with_the_cpu_backend() {
    let gpu = device();
    let mooney_rivlin = Material::MooneyRivlin(MooneyRivlin {
        c10_pa: 300.0,
        c01_pa: 200.0,
        bulk_modulus_pa: 50_000.0,
    });
    for (mesh, material, tet) in [
        (
            box_h8([EDGE_M; 3], [3, 3, 3]),
            Material::neo_hookean(1006.711409, 50_000.0),
            TetFormulation::T4,
        ),
        (
            box_t4([EDGE_M; 3], [2, 2, 2]),
            mooney_rivlin,
            TetFormulation::T4Anp,
        ),
    ] {
        let m = model_of(&mesh, material, tet, Precision::F64);
        let bcs = all_loads(&mesh);
        let dt = 0.5 * m.critical_time_step();
        let steps = (0.4 / dt) as u64;
        let mut cpu = TledSolver::new(Arc::clone(&m), &bcs, dt, StepControl::Refuse).unwrap();
        for _ in 0..steps {
            cpu.step().unwrap();
        }
        let mut g = GpuSolver::new(
            &gpu,
            m,
            &bcs,
            dt,
            StepControl::Refuse,
            GpuOptions::default(),
        )
        .unwrap();
        g.advance_steps(steps).unwrap();
        assert_eq!((g.steps(), g.time_s()), (cpu.steps(), cpu.time_s()));
        let (a, b) = (cpu.displacements(), g.displacements().unwrap());
        let d = max_distance(&a, &b);
        eprintln!(
            "{:?} {tet:?} all loads, {steps} steps: max |u| {:.3e} m, GPU-CPU {d:.3e} m",
            mesh.kind,
            largest(&a)
        );
        assert!(largest(&a) > 0.005);
        assert!(d < 1e-4 * EDGE_M, "{d}");
        // Output fields come from the CPU fields code on the downloaded state.
        let (fa, fb) = (cpu.element_fields(), g.element_fields().unwrap());
        for (x, y) in fa.von_mises_pa.iter().zip(&fb.von_mises_pa) {
            assert!(
                (x - y).abs() < 1e-3 * fa.von_mises_pa.iter().fold(0.0f64, |m, v| m.max(*v)),
                "{x} vs {y}"
            );
        }
    }
}

#[test]
fn coupling_hooks_agree_with_the_cpu_backend() {
    let gpu = device();
    let mesh = box_t4([EDGE_M; 3], [3, 3, 3]);
    let m = model(&mesh, TetFormulation::T4, Precision::F64);
    let mut bcs = BoundaryConditions::default();
    bcs.fix_nodes(&mesh.node_sets["x0"]);
    let dt = 0.5 * m.critical_time_step();
    let mut cpu = BackendSolver::Cpu(Box::new(
        TledSolver::new(Arc::clone(&m), &bcs, dt, StepControl::Refuse).unwrap(),
    ));
    let mut g = BackendSolver::Gpu(Box::new(
        GpuSolver::new(
            &gpu,
            m,
            &bcs,
            dt,
            StepControl::Refuse,
            GpuOptions::default(),
        )
        .unwrap(),
    ));
    // A "fetal head" pressing on part of the far face, deeper each coupling step.
    let pushed: Vec<u32> = mesh.node_sets["x1"]
        .iter()
        .copied()
        .filter(|&n| mesh.nodes[n as usize][1] < 0.05)
        .collect();
    for coupling_step in 1..=15 {
        let depth = -0.001 * coupling_step as f64;
        let imposed = vec![[depth, 0.0, 0.0]; pushed.len()];
        for s in [&mut cpu, &mut g] {
            s.impose_displacements(&pushed, &imposed).unwrap();
            s.advance_steps(20).unwrap();
        }
        let fa = cpu.internal_forces(&pushed).unwrap();
        let fb = g.internal_forces(&pushed).unwrap();
        let scale = largest(&fa);
        assert!(scale > 0.0);
        for (x, y) in fa.iter().flatten().zip(fb.iter().flatten()) {
            assert!(
                (x - y).abs() < 1e-3 * scale,
                "coupling step {coupling_step}: {x} vs {y}"
            );
        }
    }
    let (ua, ub) = (cpu.displacements().unwrap(), g.displacements().unwrap());
    for &n in &pushed {
        assert!(
            (ub[n as usize][0] + 0.015).abs() < 1e-7,
            "held node {n} at {:?}",
            ub[n as usize]
        );
    }
    assert!(max_distance(&ua, &ub) < 1e-4 * EDGE_M);
    // Released nodes move freely again (spring back towards the rest shape).
    for s in [&mut cpu, &mut g] {
        s.release_imposed();
        s.advance_steps(50).unwrap();
    }
    let (ua, ub) = (cpu.displacements().unwrap(), g.displacements().unwrap());
    assert!(ub[pushed[0] as usize][0] > -0.015 + 1e-4);
    assert!(max_distance(&ua, &ub) < 1e-4 * EDGE_M);
}

/// Nodes pressed onto a frictionless wall and pulled along it (sliding
/// holds): both backends keep them on the wall and let them slide alike.
#[test]
fn sliding_holds_agree_with_the_cpu_backend() {
    let gpu = device();
    let mesh = box_h8([EDGE_M; 3], [3, 3, 3]);
    let m = model(&mesh, TetFormulation::T4, Precision::F64);
    let wall = mesh.node_sets["x1"].clone();
    let mut bcs = BoundaryConditions::default();
    bcs.fix_nodes(&mesh.node_sets["x0"]);
    bcs.forces.push(NodalForce {
        nodes: wall.clone(),
        force_n: [0.0, 0.02, 0.0],
        shape: LoadShape::Step,
    });
    let dt = 0.5 * m.critical_time_step();
    let mut cpu = BackendSolver::Cpu(Box::new(
        TledSolver::new(Arc::clone(&m), &bcs, dt, StepControl::Refuse).unwrap(),
    ));
    let mut g = BackendSolver::Gpu(Box::new(
        GpuSolver::new(&gpu, m, &bcs, dt, StepControl::Refuse, GpuOptions::default()).unwrap(),
    ));
    let at = vec![[-0.002, 0.0, 0.0]; wall.len()];
    let normals = vec![[1.0, 0.0, 0.0]; wall.len()];
    for s in [&mut cpu, &mut g] {
        s.impose_sliding(&wall, &at, &normals).unwrap();
        s.advance_steps(400).unwrap();
    }
    let (ua, ub) = (cpu.displacements().unwrap(), g.displacements().unwrap());
    for &n in &wall {
        let u = ub[n as usize];
        assert!((u[0] + 0.002).abs() < 1e-7, "node {n} off the wall: {u:?}");
        assert!(u[1] > 1e-4, "node {n} did not slide: {u:?}");
    }
    assert!(max_distance(&ua, &ub) < 1e-4 * EDGE_M);
}

/// A loaded 3^3 H8 cube in f32 on `gpu` at half the critical step.
fn loaded_cube(gpu: &GpuDevice, options: GpuOptions) -> GpuSolver {
    let mesh = box_h8([EDGE_M; 3], [3, 3, 3]);
    let m = model(&mesh, TetFormulation::T4, Precision::F32);
    let dt = 0.5 * m.critical_time_step();
    GpuSolver::new(gpu, m, &all_loads(&mesh), dt, StepControl::Refuse, options).unwrap()
}

#[test]
fn snapshots_resume_bit_for_bit() {
    let mut g = loaded_cube(
        &device(),
        GpuOptions {
            max_steps_per_submission: 7,
            ..GpuOptions::default()
        },
    );
    g.advance_steps(30).unwrap();
    let snap = g.snapshot().unwrap();
    g.advance_steps(40).unwrap();
    let first = g.displacements().unwrap();
    g.restore(&snap).unwrap();
    assert_eq!(g.time_s(), snap.time_s);
    g.advance_steps(40).unwrap();
    assert_eq!(g.displacements().unwrap(), first);
}

/// Found anywhere in a submission, or in its first sub-step (one sub-step
/// per submission), an inversion is named as the CPU names it and the state
/// kept is the CPU's: the sub-step before the one that held the inverted
/// element, with every element valid.
#[test]
fn an_inverting_element_is_named_and_the_last_good_state_kept() {
    for options in [GpuOptions::default(), GpuOptions { max_steps_per_submission: 1, ..GpuOptions::default() }] {
        inversion_keeps_the_last_good_state(options);
    }
}

fn inversion_keeps_the_last_good_state(options: GpuOptions) {
    let gpu = device();
    let mesh = box_h8([EDGE_M; 3], [2, 2, 2]);
    let m = model(&mesh, TetFormulation::T4, Precision::F64);
    let mut bcs = BoundaryConditions::default();
    bcs.fix_nodes(&mesh.node_sets["x0"]);
    // The far corner node yanked back through the cube.
    bcs.forces.push(NodalForce {
        nodes: vec![mesh.node_count() as u32 - 1],
        force_n: [-20.0, -20.0, -20.0],
        shape: LoadShape::Step,
    });
    let dt = 0.5 * m.critical_time_step();
    let mut cpu = TledSolver::new(Arc::clone(&m), &bcs, dt, StepControl::Refuse).unwrap();
    let cpu_error = (0..100_000)
        .find_map(|_| cpu.step().err())
        .expect("the CPU run inverts an element");
    let mut g = GpuSolver::new(
        &gpu,
        m,
        &bcs,
        dt,
        StepControl::Refuse,
        options,
    )
    .unwrap();
    let gpu_error = g.advance_steps(100_000).unwrap_err();
    eprintln!("CPU: {cpu_error}\nGPU: {gpu_error}");
    let (element, gpu_time_s) = match (&cpu_error, &gpu_error) {
        (
            FemError::ElementInvertedDuringRun { element: a, .. },
            GpuError::Solver(FemError::ElementInvertedDuringRun {
                element: b,
                time_s,
                jacobian,
            }),
        ) => {
            assert_eq!(a, b);
            assert!(*jacobian <= 0.0);
            // f32 and f64 may cross J = 0 a sub-step apart.
            assert!(
                (time_s - cpu.time_s()).abs() <= 1.5 * dt,
                "{time_s} vs {}",
                cpu.time_s()
            );
            (*b, *time_s)
        }
        other => panic!("expected both to name an inverted element, got {other:?}"),
    };
    // The kept state is the last good one, as on the CPU: finite, the
    // named element not yet inverted, one sub-step before the error's time.
    assert!((g.time_s() - cpu.time_s()).abs() <= 1.5 * dt);
    assert!(g
        .displacements()
        .unwrap()
        .iter()
        .flatten()
        .all(|v| v.is_finite()));
    let jacobian = g.element_fields().unwrap().jacobian;
    assert!(jacobian.iter().all(|&j| j > 0.0), "element {element}: J = {}", jacobian[element]);
    let FemError::ElementInvertedDuringRun { time_s, .. } = cpu_error else { unreachable!() };
    assert!(cpu.time_s() < time_s);
    assert!(g.time_s() < gpu_time_s, "{} kept, the inversion at {gpu_time_s}", g.time_s());
    // The state one back is the CPU's too (restored from the third backup
    // or replayed): the pulled corner inverts its element after about ten
    // sub-steps, so both states have moved.
    let (gpu_snap, cpu_snap) = (g.snapshot().unwrap(), cpu.snapshot());
    assert_eq!((gpu_snap.substeps, gpu_snap.steps), (cpu_snap.substeps, cpu_snap.steps));
    for (a, b) in gpu_snap.previous_displacements_m.iter().zip(&cpu_snap.previous_displacements_m) {
        assert!((0..3).all(|c| (a[c] - b[c]).abs() <= 1e-5 * EDGE_M), "{a:?} against {b:?}");
    }
}

#[test]
fn a_buffer_over_the_device_limit_is_refused_before_allocating() {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .next()
        .expect("the GPU tests need a Vulkan adapter (CI installs lavapipe)");
    let limits = wgpu::Limits {
        max_storage_buffer_binding_size: 64 * 1024,
        ..adapter.limits()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: limits,
        ..Default::default()
    }))
    .unwrap();
    let gpu = GpuDevice::from_device(device, queue, adapter.get_info());
    let mesh = box_h8([EDGE_M; 3], [12, 12, 12]);
    let m = model(&mesh, TetFormulation::T4, Precision::F64);
    let err = GpuSolver::new(
        &gpu,
        m,
        &BoundaryConditions::default(),
        1e-5,
        StepControl::Refuse,
        GpuOptions::default(),
    )
    .err()
    .unwrap();
    let text = err.to_string();
    assert!(matches!(err, GpuError::BufferTooLarge { .. }), "{text}");
    assert!(
        text.contains("max_storage_buffer_binding_size") && text.contains("1728 elements"),
        "{text}"
    );
}

#[test]
fn auto_uses_a_real_gpu_or_falls_back_to_the_cpu_with_a_notice() {
    let mesh = box_h8([EDGE_M; 3], [2, 2, 2]);
    let m = model(&mesh, TetFormulation::T4, Precision::F64);
    let real_gpu = GpuDevice::headless(AdapterChoice::RealGpuOnly).is_ok();
    let opened = open_solver(
        Backend::Auto,
        Arc::clone(&m),
        &BoundaryConditions::default(),
        1e-5,
        StepControl::Refuse,
        GpuOptions::default(),
    )
    .unwrap();
    if real_gpu {
        assert_eq!(
            (opened.solver.backend(), opened.notice),
            (Backend::Gpu, None)
        );
    } else {
        assert_eq!(opened.solver.backend(), Backend::Cpu);
        let notice = opened.notice.expect("a fallback notice");
        assert!(
            notice.contains("running on the CPU") && notice.contains("mesa-vulkan-drivers"),
            "{notice}"
        );
    }
    // `gpu` takes lavapipe where there is no real GPU.
    let opened = open_solver(
        Backend::Gpu,
        m,
        &BoundaryConditions::default(),
        1e-5,
        StepControl::Refuse,
        GpuOptions::default(),
    )
    .unwrap();
    assert_eq!(opened.solver.backend(), Backend::Gpu);
    assert!(opened.solver.adapter_name().is_some());
}

#[test]
fn the_bench_reports_the_cpu_bench_figures_and_bandwidth() {
    let r = carus_fem::gpu::bench_tled(&device(), carus_fem::ElementKind::H8, 4, 20, None, Some(100.0))
        .unwrap();
    assert_eq!(
        (r.elements, r.nodes, r.steps, r.threads, r.backend.as_str()),
        (64, 125, 20, 64, "gpu")
    );
    assert!(
        r.wall_s > 0.0 && (r.us_per_element_step * r.element_steps_per_s - 1e6).abs() < 1e-6 * 1e6
    );
    assert!(
        (r.achieved_bandwidth_gbs - r.bytes_per_element_step * r.element_steps_per_s / 1e9).abs()
            < 1e-9 * r.achieved_bandwidth_gbs
    );
    assert_eq!(
        (r.peak_bandwidth_gbs, r.peak_source.as_deref()),
        (Some(100.0), Some("--peak-gbs"))
    );
    let json = serde_json::to_value(&r).unwrap();
    for key in [
        "elements",
        "nodes",
        "steps",
        "wall_s",
        "us_per_element_step",
        "element_steps_per_s",
        "threads",
        "backend",
        "achieved_bandwidth_gbs",
        "adapter",
    ] {
        assert!(json.get(key).is_some(), "{key}");
    }
}

#[test]
fn a_lost_device_is_an_error_not_a_hang_and_the_state_read_before_survives() {
    let gpu = device();
    let mut g = loaded_cube(&gpu, GpuOptions::default());
    g.advance_steps(20).unwrap();
    let before = g.displacements().unwrap();
    assert!(largest(&before) > 0.0);
    // What a driver reset or an unplugged eGPU does to the device.
    gpu.device().destroy();
    let started = std::time::Instant::now();
    let err = g
        .advance_steps(20)
        .and_then(|()| g.displacements().map(|_| ()))
        .unwrap_err();
    assert!(
        started.elapsed() < GpuOptions::default().wait_timeout,
        "the lost device was waited on"
    );
    let text = err.to_string();
    assert!(
        matches!(err, GpuError::DeviceLost { .. } | GpuError::Device { .. }),
        "{text}"
    );
    eprintln!("after device loss: {text}");
    // What was read before the loss is the caller's, untouched.
    assert!(largest(&before) > 0.0);
}
