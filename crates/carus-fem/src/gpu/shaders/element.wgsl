// Element kernel: one invocation per element. Deformation gradient, second
// Piola-Kirchhoff stress of the decoupled isotropic law (neo-Hookean and
// Mooney-Rivlin), nodal forces w F S dh and Flanagan-Belytschko hourglass
// forces, written to the element's force copies (kernel/element.rs on the CPU).

@group(0) @binding(2) var<storage, read> connectivity: array<u32>;
@group(0) @binding(3) var<storage, read> shape_derivatives: array<f32>;
@group(0) @binding(4) var<storage, read> weight: array<f32>;
@group(0) @binding(5) var<storage, read> coefficients: array<f32>;
// H8: hourglass vectors sqrt(k) gamma; T4ANP: nodal dilatation; else unused.
@group(0) @binding(6) var<storage, read> extra: array<f32>;
@group(0) @binding(7) var<storage, read> displacement: array<f32>;
@group(0) @binding(8) var<storage, read_write> forces: array<f32>;
@group(0) @binding(9) var<storage, read_write> status: array<atomic<u32>, 4>;

fn node_displacement(n: u32) -> vec3<f32> {
    return vec3<f32>(displacement[3u * n], displacement[3u * n + 1u], displacement[3u * n + 2u]);
}

// J^(-1/3): pow, then one Newton step y <- y (4 - J y^3) / 3 for full f32 accuracy.
fn inv_cbrt(j: f32) -> f32 {
    let y = pow(j, -1.0 / 3.0);
    return y * (4.0 - j * y * y * y) / 3.0;
}

@compute @workgroup_size(WORKGROUP)
fn element_forces(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let e = flat_index(wg, groups, local);
    if (e >= params.element_count) {
        return;
    }
    let lane = e % LANES;
    var u: array<vec3<f32>, NPE>;
    var dh: array<vec3<f32>, NPE>;
    // F = I + sum_a u_a dh_a^T (columns: F[j] = d x / d X_j).
    var f = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    var j_mean = 0.0;
    for (var a = 0u; a < NPE; a++) {
        let n = connectivity[block_offset(e, a, 1u)];
        u[a] = node_displacement(n);
        let d = block_offset(e, a, 3u);
        dh[a] = vec3<f32>(shape_derivatives[d], shape_derivatives[d + LANES], shape_derivatives[d + 2u * LANES]);
        f[0] += u[a] * dh[a].x;
        f[1] += u[a] * dh[a].y;
        f[2] += u[a] * dh[a].z;
        if (ANP) {
            j_mean += extra[n];
        }
    }
    let j = determinant(f);
    if (!(j > 0.0)) {
        atomicMin(&status[0], step.index);
        atomicMin(&status[1], e);
    }
    let c = transpose(f) * f;
    // J_vol: the element's own J, or the T4ANP nodal average (Joldes et al. 2009).
    var j_vol = j;
    if (ANP) {
        j_vol = j_mean / f32(NPE);
    }
    let block = e / LANES * 3u * LANES + lane;
    let c10 = coefficients[block];
    let c01 = coefficients[block + LANES];
    let kappa = coefficients[block + 2u * LANES];
    // C^-1 from the adjugate; det C = J^2.
    let inv_det_c = 1.0 / (j * j);
    let ci = mat3x3<f32>(
        vec3<f32>(c[1][1] * c[2][2] - c[1][2] * c[1][2], c[0][2] * c[1][2] - c[0][1] * c[2][2], c[0][1] * c[1][2] - c[1][1] * c[0][2]),
        vec3<f32>(c[0][2] * c[1][2] - c[0][1] * c[2][2], c[0][0] * c[2][2] - c[0][2] * c[0][2], c[0][1] * c[0][2] - c[0][0] * c[1][2]),
        vec3<f32>(c[0][1] * c[1][2] - c[1][1] * c[0][2], c[0][1] * c[0][2] - c[0][0] * c[1][2], c[0][0] * c[1][1] - c[0][1] * c[0][1]),
    ) * inv_det_c;
    let i1 = c[0][0] + c[1][1] + c[2][2];
    let tr_c2 = c[0][0] * c[0][0] + c[1][1] * c[1][1] + c[2][2] * c[2][2]
        + 2.0 * (c[0][1] * c[0][1] + c[1][2] * c[1][2] + c[0][2] * c[0][2]);
    let i2 = 0.5 * (i1 * i1 - tr_c2);
    let y = inv_cbrt(j);
    let y2 = y * y;
    // W = c10 (I1bar - 3) + c01 (I2bar - 3) + kappa/2 (J_vol - 1)^2.
    let a1 = 2.0 * c10 * y2;
    let a2 = 2.0 * c01 * y2 * y2;
    let p_vol = j * kappa * (j_vol - 1.0);
    let ci_coef = p_vol - a1 * i1 / 3.0 - a2 * 2.0 / 3.0 * i2;
    let diag = a1 + a2 * i1;
    let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    let s = identity * diag - c * a2 + ci * ci_coef;
    // First Piola-Kirchhoff times the integration weight: f_a = w F S dh_a.
    let p = (f * s) * weight[e];
    var out: array<vec3<f32>, NPE>;
    for (var a = 0u; a < NPE; a++) {
        out[a] = p * dh[a];
    }
    if (HOURGLASS) {
        // q_g = sum_a s_g,a u_a; f_a += sum_g s_g,a q_g (stiffness form).
        // Layout [((block * 4 + g) * 8 + a) * LANES + lane] (kernel::blocks).
        // Each s_g,a is loaded once and kept for the second sum.
        for (var g = 0u; g < 4u; g++) {
            let base = (e / LANES * 4u + g) * NPE * LANES + lane;
            var s_g: array<f32, NPE>;
            var q = vec3<f32>(0.0);
            for (var a = 0u; a < NPE; a++) {
                s_g[a] = extra[base + a * LANES];
                q += s_g[a] * u[a];
            }
            for (var a = 0u; a < NPE; a++) {
                out[a] += s_g[a] * q;
            }
        }
    }
    for (var a = 0u; a < NPE; a++) {
        let o = block_offset(e, a, 3u);
        forces[o] = out[a].x;
        forces[o + LANES] = out[a].y;
        forces[o + 2u * LANES] = out[a].z;
    }
}
