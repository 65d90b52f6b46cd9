//! End to end: the shipped example jobs run through `carus_io::job`. The
//! cube (VALIDATION.md V3 at n = 5, from a Gmsh file) is checked against
//! the same cube built directly with carus-fem's API; the pad (tetrahedra
//! from an Abaqus file in mm, pressure, gravity) against statics.

use std::path::{Path, PathBuf};

use carus_fem::validation::cube::{simulate, CubeElement, CubeSetup, CubeVariant};
use carus_io::job::{run_job, JobError, RunOptions};
use carus_io::vtk::read_vtk_arrays;
use carus_io::PvdCollection;

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cube_extension.toml")
}

fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("carus-io-e2e-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn the_example_job_matches_the_direct_api_and_writes_readable_results() {
    let out = fresh_dir("cube");
    let mut progress_calls = 0;
    let report = run_job(&example(), &out, &RunOptions::default(), &mut |_| {
        progress_calls += 1
    })
    .unwrap();
    assert!(report.failure.is_none(), "{:?}", report.failure);
    assert_eq!(
        (report.elements, report.nodes, report.element_kind),
        (125, 216, "h8")
    );
    assert_eq!((report.tet_formulation, report.hourglass_modulus), (None, Some("shear")));
    assert_eq!(report.steps, 5000);
    assert!((report.simulated_s - 10.0).abs() < 1e-9);
    assert_eq!(report.frames, 21, "t = 0, every 0.5 s to 10 s");
    assert!(progress_calls >= 20);
    assert!(report.dt_s <= report.critical_dt_s);

    // The same model through carus-fem directly (the V3 set-up, n = 5,
    // with the example's hourglass scaling, the solver's default).
    let setup = CubeSetup {
        hourglass_modulus: carus_fem::HourglassModulus::Shear,
        ..CubeSetup::miller(5, CubeElement::H8, CubeVariant::Clamped)
    };
    let direct = simulate(&setup).unwrap();
    let frames =
        PvdCollection::parse(&std::fs::read_to_string(out.join("solution.pvd")).unwrap()).unwrap();
    assert_eq!(frames.frames().len(), 21);
    let (last_time, last_file) = frames.frames().last().unwrap().clone();
    assert!((last_time - 10.0).abs() < 1e-9);
    let last = out.join(&last_file);
    let mesh = carus_io::read_mesh(&last).unwrap().mesh;
    let arrays = read_vtk_arrays(&last).unwrap();
    let displacement = &arrays.point["displacement"].values;
    let reference = CubeSetup::miller(5, CubeElement::H8, CubeVariant::Clamped).mesh();
    let mut worst = 0.0f64;
    for (node, x) in mesh.nodes.iter().enumerate() {
        let twin = reference
            .nodes
            .iter()
            .position(|y| (0..3).all(|k| (x[k] - y[k]).abs() < 1e-9))
            .expect("every node of the Gmsh cube is a node of the generated cube");
        for k in 0..3 {
            worst = worst.max((displacement[3 * node + k] - direct.displacements_m[twin][k]).abs());
        }
    }
    assert!(worst < 1e-9, "job and direct API differ by {worst} m");
    let reaction = report.reactions_n["x0"];
    let direct_reaction = direct.reaction_fixed_face_n;
    assert!(
        (reaction[0] - direct_reaction[0]).abs() < 1e-6 * direct_reaction[0].abs(),
        "{reaction:?} vs {direct_reaction:?}"
    );
    assert!(
        reaction[0] < 0.0,
        "the fixed face holds the cube back along -x"
    );
    assert!(
        (report.reactions_n["x1"][0] + reaction[0]).abs() < 0.01 * reaction[0].abs(),
        "at rest the two supports balance"
    );
    assert!((report.max_displacement_m - 0.03).abs() < 1e-9);
    assert!(arrays.cell["von_mises_pa"]
        .values
        .iter()
        .all(|v| v.is_finite() && *v > 0.0));
    assert!(arrays.cell["jacobian"]
        .values
        .iter()
        .all(|j| *j > 0.5 && *j < 1.5));

    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..3], ["time_s", "step", "max_displacement_m"]);
    assert!(header.contains(&"reaction_x0_x_n"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 201, "t = 0 and every 0.05 s");
    // The example is fit to copy: at rest, under 1 % of its strain energy
    // is in hourglass modes (V3's criterion).
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let last: Vec<f64> = rows[200].split(',').map(|v| v.parse().unwrap()).collect();
    let share = last[column("hourglass_j")] / last[column("strain_j")];
    assert!(share < 0.01, "hourglass energy {share:.4} of the strain energy");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 5000);

    // A second run into the same folder is refused, and leaves it as it was.
    let again = run_job(&example(), &out, &RunOptions::default(), &mut |_| {});
    assert!(matches!(again, Err(JobError::OutDirExists { .. })));
    assert_eq!(summary["steps"], serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()["steps"]);

    // A run stopped part way (Ctrl-C) writes its state then as the last
    // frame, its history and summary, and says it was stopped.
    std::fs::remove_dir_all(&out).unwrap();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let options = RunOptions { stop: Some(stop.clone()) };
    let stopped = run_job(&example(), &out, &options, &mut |p| {
        if p.steps >= 1000 {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    })
    .unwrap();
    assert!(stopped.failure.as_deref().is_some_and(|f| f.contains("stopped by the user")), "{:?}", stopped.failure);
    assert!(stopped.steps >= 1000 && stopped.steps < 5000, "{}", stopped.steps);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], stopped.steps);
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), stopped.frames);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn the_pad_example_sags_under_pressure_and_gravity() {
    let out = fresh_dir("pad");
    let job = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/pad_pressure.toml");
    let report = run_job(&job, &out, &RunOptions::default(), &mut |_| {}).unwrap();
    assert!(report.failure.is_none(), "{:?}", report.failure);
    assert_eq!(
        (report.element_kind, report.elements, report.nodes),
        ("t4", 432, 147)
    );
    // The summary says which tetrahedron the job asked for.
    assert_eq!((report.tet_formulation, report.hourglass_modulus), (Some("t4anp"), None));
    assert!(report.dt_s < report.critical_dt_s);
    // Read in millimetres, scaled to metres: the pad is 20 mm wide.
    let last = out.join(format!("frames/frame_{:05}.vtu", report.frames - 1));
    let mesh = carus_io::read_mesh(&last).unwrap().mesh;
    let width = mesh.nodes.iter().map(|p| p[0]).fold(0.0, f64::max);
    assert!((width - 0.02).abs() < 1e-12);
    // The centre of the top face moves down, nearly the most of all nodes.
    let u = &read_vtk_arrays(&last).unwrap().point["displacement"].values;
    let centre = mesh
        .nodes
        .iter()
        .position(|p| {
            (p[0] - 0.01).abs() < 1e-9 && (p[1] - 0.01).abs() < 1e-9 && (p[2] - 0.004).abs() < 1e-9
        })
        .unwrap();
    let sag = -u[3 * centre + 2];
    assert!(
        sag > 0.9 * report.max_displacement_m,
        "sag {sag} m, largest {} m",
        report.max_displacement_m
    );
    // Kirchhoff's clamped square plate, w = 0.00126 q a^4 / D, under the
    // pressure and the weight per area (rho g h): 0.90 mm, plate theory's
    // stiff bound. At a/h = 5 shear deflection (Mindlin) adds much to it and
    // two layers of linear tetrahedra take some back: 1.02 mm measured.
    let (a, h, e, nu) = (0.02f64, 0.004f64, 3000.0, 0.45);
    let thin = 0.00126 * (50.0 + 1000.0 * 9.81 * h) * a.powi(4) / (e * h.powi(3) / (12.0 * (1.0 - nu * nu)));
    assert!(sag > thin && sag < 1.3 * thin, "sag {sag} m, thin plate {thin} m");
    // Equilibrium, from the input mesh: the rim carries the pressure (50 Pa
    // on the 20 x 20 mm top) and the weight, less the shares of both that
    // act on rim nodes themselves (A / 3 of each top triangle, V / 4 of each
    // tetrahedron, lumped).
    let input = carus_io::read_mesh(&job.with_file_name("pad_t4.inp")).unwrap().to_metres(carus_io::LengthUnit::Millimetre).mesh;
    let on_rim: Vec<bool> = {
        let mut on = vec![false; input.nodes.len()];
        input.node_sets["rim"].iter().for_each(|&n| on[n as usize] = true);
        on
    };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let (mut area, mut pressure_on_rim) = (0.0, 0.0);
    for t in &input.surfaces["top"] {
        let [a, b, c] = t.map(|n| input.nodes[n as usize]);
        let n = cross(sub(b, a), sub(c, a));
        let share = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() / 3.0;
        area += 3.0 * share;
        pressure_on_rim += 50.0 * share * t.iter().filter(|&&n| on_rim[n as usize]).count() as f64;
    }
    let (mut volume, mut weight_on_rim) = (0.0, 0.0);
    for tet in input.connectivity.chunks(4) {
        let [a, b, c, d] = [0, 1, 2, 3].map(|k| input.nodes[tet[k] as usize]);
        let n = cross(sub(b, a), sub(c, a));
        let v = (n[0] * (d[0] - a[0]) + n[1] * (d[1] - a[1]) + n[2] * (d[2] - a[2])).abs() / 6.0;
        volume += v;
        weight_on_rim += 1000.0 * 9.81 * v / 4.0 * tet.iter().filter(|&&n| on_rim[n as usize]).count() as f64;
    }
    assert!((area - 4e-4).abs() < 1e-12 && (volume - 1.6e-6).abs() < 1e-15, "{area} m^2, {volume} m^3");
    let load = 50.0 * area + 1000.0 * volume * 9.81;
    let rim = report.reactions_n["rim"];
    assert!(
        (rim[2] + pressure_on_rim + weight_on_rim - load).abs() < 0.01 * load,
        "rim reaction {rim:?} + {pressure_on_rim} N of pressure and {weight_on_rim} N of weight on the rim, against {load} N"
    );
    assert!(rim[0].abs() < 0.01 * load && rim[1].abs() < 0.01 * load, "no sideways load: {rim:?}");
    std::fs::remove_dir_all(&out).unwrap();
}

fn write_job(dir: &Path, body: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cube_n5.msh"),
        dir.join("cube_n5.msh"),
    )
    .unwrap();
    let path = dir.join("job.toml");
    std::fs::write(&path, body).unwrap();
    path
}

const BASE: &str = r#"
[mesh]
file = "cube_n5.msh"
length_unit = "mm"

[[material]]
law = "neo_hookean"
young_modulus_pa = 3000.0
poisson_ratio = 0.45
density_kg_m3 = 1000.0

[[fixed]]
node_set = "x0"
"#;

#[test]
fn a_run_that_inverts_an_element_stops_with_its_last_good_frame() {
    // The cube read in millimetres (0.1 mm) and crushed by 0.3 mm in 1 ms: it inverts.
    let dir = fresh_dir("invert");
    let body = format!(
        "{BASE}\n[[displacement]]\nnode_set = \"x1\"\nx_m = -3e-4\nload = {{ shape = \"ramp\", duration_s = 1e-3 }}\n\n[solver]\nend_time_s = 0.01\ntime_step_s = \"auto\"\n"
    );
    let job = write_job(&dir, &body);
    let out = dir.join("out");
    let report = run_job(&job, &out, &RunOptions::default(), &mut |_| {}).unwrap();
    let failure = report.failure.clone().expect("the crushed cube must fail");
    assert!(
        failure.contains("element") && failure.contains("step"),
        "{failure}"
    );
    assert!(
        failure.contains("cube_n5.msh"),
        "names the element's id in the mesh file: {failure}"
    );
    // A pull larger than the mesh is noted as a likely unit slip.
    assert!(
        report.notes.iter().any(|n| n.contains("displacement[0] on `x1`") && n.contains("times the mesh's size") && n.contains("length_unit = \"mm\"")),
        "{:?}",
        report.notes
    );
    let frames =
        PvdCollection::parse(&std::fs::read_to_string(out.join("solution.pvd")).unwrap()).unwrap();
    assert_eq!(frames.frames().len(), report.frames);
    let (time, file) = frames.frames().last().unwrap();
    assert!(
        (time - report.simulated_s).abs() < 1e-15,
        "the last frame is the last good state"
    );
    assert!(out.join(file).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A history interval longer than the run still gives the row at its end,
/// and the summary's reactions are that row's, at the end.
#[test]
fn the_history_ends_with_the_end_and_the_reactions_are_its() {
    let dir = fresh_dir("history-end");
    let body = format!(
        "{BASE}\n[[displacement]]\nnode_set = \"x1\"\nx_m = 1e-5\nload = {{ shape = \"ramp\", duration_s = 1e-2 }}\n\n[solver]\nend_time_s = 0.01\ntime_step_s = \"auto\"\n\n[output]\nhistory_interval_s = 100.0\n"
    );
    let job = write_job(&dir, &body);
    let out = dir.join("out");
    let report = run_job(&job, &out, &RunOptions::default(), &mut |_| {}).unwrap();
    assert!(report.failure.is_none(), "{:?}", report.failure);
    let table = carus_io::CsvTable::read(&out.join("history.csv")).unwrap();
    let cell = |name: &str, row: usize| table.number(&table.rows[row], table.column(name).unwrap()).unwrap().unwrap();
    assert_eq!(table.rows.len(), 2, "the start and the end");
    assert_eq!(cell("time_s", 1), report.simulated_s);
    let reaction = report.reactions_n["x1"];
    assert!(reaction[0].abs() > 0.0, "{reaction:?}");
    assert_eq!(cell("reaction_x1_x_n", 1), reaction[0]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn job_errors_name_the_key_the_line_and_the_fix() {
    let dir = fresh_dir("errors");
    let cases: [(&str, &str); 12] = [
        (
            "\n[solver]\nend_time_s = 1.0\ntime_stepp_s = 1e-3\n",
            "job.toml:17:1: `solver.time_stepp_s`: unknown field `time_stepp_s`",
        ),
        ("\n[solver]\nend_time_s = -1.0\n", "job.toml:16: `solver.end_time_s`: -1 must be positive"),
        (
            "\n[[displacement]]\nnode_set = \"x9\"\nx_m = 0.001\nload = { shape = \"step\" }\n[solver]\nend_time_s = 1.0\n",
            "job.toml:16: `displacement[0].node_set` names the node set \"x9\", which the mesh does not have; fix: use one of: x0, x1",
        ),
        (
            "\n[solver]\nend_time_s = 1.0\ntime_step_s = 0.5\n",
            "job.toml:17: `solver.time_step_s`: time step 5.000000e-1 s is above the critical time step",
        ),
        (
            "\n[[pressure]]\nsurface = \"x1\"\npressure_pa = 10.0\nload = { shape = \"ramp_hold\", ramp = 1.0 }\n[solver]\nend_time_s = 1.0\n",
            "job.toml:18:8: `pressure[0].load`: unknown field `ramp`",
        ),
        ("\n[solver]\nend_time_s = 1.0\nhourglass_coefficient = \"high\"\n", "job.toml:17:25: `solver.hourglass_coefficient`: invalid type"),
        // A vector's stray number is refused, not dropped; too few are too.
        (
            "\n[gravity]\nacceleration_m_s2 = [0.0, 0.0, -9.81, 5.0]\n[solver]\nend_time_s = 1.0\n",
            "job.toml:16:21: `gravity.acceleration_m_s2`: 4 numbers where a vector has 3; give [x, y, z]",
        ),
        (
            "\n[[force]]\nnode_set = \"x1\"\ntotal_force_n = [0.0, 0.0, -0.01, 99.0]\nload = { shape = \"step\" }\n[solver]\nend_time_s = 1.0\n",
            "job.toml:17:17: `force[0].total_force_n`: 4 numbers where a vector has 3; give [x, y, z]",
        ),
        (
            "\n[[force]]\nnode_set = \"x1\"\nforce_per_node_n = [0.0, -0.01]\nload = { shape = \"step\" }\n[solver]\nend_time_s = 1.0\n",
            "job.toml:17:20: `force[0].force_per_node_n`: 2 numbers where a vector has 3; give [x, y, z]",
        ),
        // A node held twice: one table would silently override the other.
        (
            "\n[[displacement]]\nnode_set = \"x0\"\nx_m = 0.001\nload = { shape = \"step\" }\n[solver]\nend_time_s = 1.0\n",
            "job.toml:16: `displacement[0].node_set`: node 1 (the mesh file's number) is already held in x by fixed[0]",
        ),
        // Steps so small that the run could not end, set or implied.
        ("\n[solver]\nend_time_s = 1.0\ntime_step_s = 1e-300\n", "job.toml:17: `solver.time_step_s`: 1e-300 s would take 1.0e300 steps"),
        (
            "\n[solver]\nend_time_s = 1.0\ntime_step_s = \"auto\"\n",
            // No one key sets the stable step, so no line is named.
            "job.toml: `materials`: the stable time step is 1.875e-157 s, so 1 s would take 5.3e156 steps",
        ),
    ];
    for (extra, expected) in cases {
        let base = if expected.contains("`materials`") { BASE.replace("density_kg_m3 = 1000.0", "density_kg_m3 = 1e-300") } else { BASE.to_string() };
        let job = write_job(&dir, &format!("{base}{extra}"));
        let err = run_job(&job, &dir.join("out"), &RunOptions::default(), &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(err.contains(expected), "{err}\n  expected: {expected}");
        assert!(err.contains("fix:") || err.contains("hint:"), "{err}");
    }
    // A mesh path that names nothing: the key, where it was looked for, and why there.
    let job = write_job(&dir, &format!("{}\n[solver]\nend_time_s = 1.0\n", BASE.replace("cube_n5.msh", "nope.msh")));
    let err = run_job(&job, &dir.join("out"), &RunOptions::default(), &mut |_| {}).unwrap_err().to_string();
    let looked_for = dir.join("nope.msh");
    assert!(err.contains(&format!("job.toml:3: `mesh.file`: \"nope.msh\" names {}, which does not exist", looked_for.display())), "{err}");
    assert!(err.contains("starts at the job file's folder"), "{err}");
    // The automatic step ends the run on end_time_s itself: whole steps of at most 0.9
    // of the critical one, and one step where the run is shorter than that.
    for (density, end_s) in [("1000.0", 0.2), ("1e308", 0.2)] {
        let job = write_job(&dir, &format!("{}\n[solver]\nend_time_s = {end_s}\n", BASE.replace("density_kg_m3 = 1000.0", &format!("density_kg_m3 = {density}"))));
        let out = dir.join(format!("out-auto-{density}"));
        let report = run_job(&job, &out, &RunOptions::default(), &mut |_| {}).unwrap();
        assert!(report.failure.is_none(), "{:?}", report.failure);
        assert_eq!(report.simulated_s, end_s);
        assert!(report.steps >= 1 && report.dt_s <= 0.9 * report.critical_dt_s * (1.0 + 1e-12), "{report:?}");
        assert!((report.dt_s * report.steps as f64 - end_s).abs() < 1e-12, "{report:?}");
    }
    // A key written twice is named, and so is a component listed twice.
    let twice = write_job(&dir, &format!("{BASE}\n[solver]\nend_time_s = 1e-4\nend_time_s = 2e-4\n"));
    let err = run_job(&twice, &dir.join("out"), &RunOptions::default(), &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("job.toml:17:1: duplicate key `end_time_s`: given a second time in its table") && err.contains("keep one of the two lines"), "{err}");
    let listed = write_job(&dir, &format!("{BASE}components = [\"x\", \"x\", \"y\"]\n[solver]\nend_time_s = 1e-4\n"));
    let err = run_job(&listed, &dir.join("out"), &RunOptions::default(), &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("job.toml:14: `fixed[0].components`: names \"x\" twice"), "{err}");
    // Young/Poisson with a shear modulus too: one of them would be ignored.
    let both = write_job(&dir, &format!("{}\n[solver]\nend_time_s = 1e-4\n", BASE.replace("poisson_ratio = 0.45", "poisson_ratio = 0.45\nshear_modulus_pa = 500.0")));
    let err = run_job(&both, &dir.join("out"), &RunOptions::default(), &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("job.toml:6: `material[0]`: moduli from both pairs"), "{err}");
    // Two fixings of one node agree, so they are not refused.
    let twice = write_job(&dir, &format!("{BASE}\n[[fixed]]\nnode_set = \"x0\"\ncomponents = [\"x\"]\n[solver]\nend_time_s = 1e-4\n"));
    run_job(&twice, &dir.join("out-twice"), &RunOptions::default(), &mut |_| {}).unwrap();
    // The critical-step error names the job's own way out.
    let too_long = write_job(&dir, &format!("{BASE}\n[solver]\nend_time_s = 1.0\ntime_step_s = 0.5\n"));
    let err = run_job(&too_long, &dir.join("out"), &RunOptions::default(), &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("sub_stepping = true") && !err.contains("StepControl"), "{err}");
    // The density is also read as scenarios spell it.
    let spelt = write_job(&dir, &format!("{}\n[solver]\nend_time_s = 1e-4\n", BASE.replace("density_kg_m3", "density_kg_per_m3")));
    run_job(&spelt, &dir.join("out-spelt"), &RunOptions::default(), &mut |_| {}).unwrap();
    let unit = write_job(&dir, &BASE.replace("\"mm\"", "\"cm\""));
    let err = run_job(&unit, &dir.join("out"), &RunOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("job.toml:4:15: `mesh.length_unit`") && err.contains("expected `m` or `mm`"),
        "{err}"
    );
    let typo = write_job(
        &dir,
        &format!("{BASE}\n[solver]\nend_time_s = 1.0\ndamping_pers = 1.0\n"),
    );
    let err = run_job(&typo, &dir.join("out"), &RunOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("job.toml:17:1: `solver.damping_pers`") && err.contains("did you mean `damping_per_s`?"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An output interval shorter than the step writes at every step, and the
/// summary says so, with how many it wrote.
#[test]
fn an_interval_shorter_than_the_step_is_noted() {
    let dir = fresh_dir("interval-below-step");
    let body = format!(
        "{BASE}\n[solver]\nend_time_s = 1e-4\ntime_step_s = \"auto\"\n\n[output]\nframe_interval_s = 1e-12\nhistory_interval_s = 1e-12\n"
    );
    let job = write_job(&dir, &body);
    let out = dir.join("out");
    let report = run_job(&job, &out, &RunOptions::default(), &mut |_| {}).unwrap();
    assert!(report.failure.is_none(), "{:?}", report.failure);
    assert_eq!(report.frames as u64, report.steps + 1, "the start and every step");
    let steps = format!("at every step ({} steps)", report.steps);
    for key in ["output.frame_interval_s = 1.000e-12 s", "output.history_interval_s = 1.000e-12 s"] {
        assert!(
            report.notes.iter().any(|n| n.starts_with(key) && n.contains("shorter than the time step") && n.contains(&steps)),
            "{key}: {:?}",
            report.notes
        );
    }
    // A spacing of whole steps is not noted.
    let body = format!("{BASE}\n[solver]\nend_time_s = 1e-4\ntime_step_s = \"auto\"\n");
    let job = write_job(&dir, &body);
    let report = run_job(&job, &dir.join("out-default"), &RunOptions::default(), &mut |_| {}).unwrap();
    assert!(!report.notes.iter().any(|n| n.contains("shorter than the time step")), "{:?}", report.notes);
    std::fs::remove_dir_all(&dir).unwrap();
}
