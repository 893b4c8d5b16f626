// Quadratic B-spline weights of MPM (docs/method.md §2) in f32: the WGSL twin of src/sim/bspline.rs.
//
// For a particle at x and grid spacing Δx (passed as inv_dx = 1/Δx and dx):
// base = floor(x/Δx − 0.5), fx = x/Δx − base (each component in [0.5, 1.5), up to one ulp
// of rounding at the ends), and per axis
//   w0 = ½ (1.5 − f)²    dw0/df = f − 1.5
//   w1 = ¾ − (f − 1)²    dw1/df = −2 (f − 1)
//   w2 = ½ (f − 0.5)²    dw2/df = f − 0.5
// Node base + off, off ∈ {0,1,2}³, gets w = w[off.x].x · w[off.y].y · w[off.z].z;
// d_ip = i·Δx − x_p = (off − fx)·Δx (from fx, so it does not depend on the size of x);
// ∇w = (dw_a w_b w_c, w_a dw_b w_c, w_a w_b dw_c) / Δx. The MLS factor 4/Δx² of docs/method.md §2 is
// D_p⁻¹ (Σ w d dᵀ = Δx²/4 I).
//
// f32 note: x/Δx carries an absolute error of ~ε·|x|/Δx, so fx and the weights do too
// (~2e-5 at 300 cells from the origin); keep the domain's origin near the particles.

struct BsplineStencil {
    // lowest node of the 3×3×3 stencil, floor(x/Δx − 0.5)
    base: vec3<i32>,
    // x/Δx − base
    fx: vec3<f32>,
    // w[a]: weight of offset a ∈ {0,1,2} on each axis (x, y, z components)
    w: array<vec3<f32>, 3>,
    // dw[a]: derivative of w[a] with respect to fx (times inv_dx: with respect to x)
    dw: array<vec3<f32>, 3>,
}

// The stencil of a particle at x on a grid with node i at i·Δx, inv_dx = 1/Δx.
fn bspline_stencil(x: vec3<f32>, inv_dx: f32) -> BsplineStencil {
    let xs = x * inv_dx;
    let base_f = floor(xs - 0.5);
    let fx = xs - base_f;
    var s: BsplineStencil;
    s.base = vec3<i32>(base_f);
    s.fx = fx;
    s.w = bspline_axis_weights(fx);
    s.dw = bspline_axis_slopes(fx);
    return s;
}

// w[a], a ∈ {0,1,2}: the per-axis weights of the stencil's offsets at fx = x/Δx − base.
fn bspline_axis_weights(fx: vec3<f32>) -> array<vec3<f32>, 3> {
    let d0 = 1.5 - fx;
    let d1 = fx - 1.0;
    let d2 = fx - 0.5;
    return array<vec3<f32>, 3>(0.5 * d0 * d0, 0.75 - d1 * d1, 0.5 * d2 * d2);
}

// dw[a]: the derivatives of bspline_axis_weights with respect to fx.
fn bspline_axis_slopes(fx: vec3<f32>) -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(fx - 1.5, -2.0 * (fx - 1.0), fx - 0.5);
}

// Weight of offset off ∈ {0,1,2}³ from a stencil known by fx alone (bspline_weight).
fn bspline_weight_at(fx: vec3<f32>, off: vec3<u32>) -> f32 {
    let w = bspline_axis_weights(fx);
    let p = bspline_pick(w[0], w[1], w[2], off);
    return p.x * p.y * p.z;
}

// Weight w_ip of node base + off, off ∈ {0,1,2}³.
fn bspline_weight(s: BsplineStencil, off: vec3<u32>) -> f32 {
    let w = bspline_pick(s.w[0], s.w[1], s.w[2], off);
    return w.x * w.y * w.z;
}

// (a[off.x].x, a[off.y].y, a[off.z].z) of the three per-axis values a0, a1, a2. Selects
// rather than an index: a runtime index into a local array sends it to memory on CPU
// drivers (lavapipe), and this runs 27 times per particle in every transfer.
fn bspline_pick(a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>, off: vec3<u32>) -> vec3<f32> {
    return select(select(a0, a1, off == vec3<u32>(1u)), a2, off == vec3<u32>(2u));
}

// Gradient ∇_x w_ip of node base + off with respect to the particle position.
fn bspline_weight_grad(s: BsplineStencil, off: vec3<u32>, inv_dx: f32) -> vec3<f32> {
    let w = bspline_pick(s.w[0], s.w[1], s.w[2], off);
    let dw = bspline_pick(s.dw[0], s.dw[1], s.dw[2], off);
    return vec3<f32>(dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z) * inv_dx;
}

// The same from a stencil known by fx alone.
fn bspline_weight_grad_at(fx: vec3<f32>, off: vec3<u32>, inv_dx: f32) -> vec3<f32> {
    let aw = bspline_axis_weights(fx);
    let adw = bspline_axis_slopes(fx);
    let w = bspline_pick(aw[0], aw[1], aw[2], off);
    let dw = bspline_pick(adw[0], adw[1], adw[2], off);
    return vec3<f32>(dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z) * inv_dx;
}

// Offset d_ip = i·Δx − x_p of node base + off from the particle.
fn bspline_offset(s: BsplineStencil, off: vec3<u32>, dx: f32) -> vec3<f32> {
    return (vec3<f32>(off) - s.fx) * dx;
}

// Offset (a, b, c) ∈ {0,1,2}³ of stencil node n ∈ [0, 27), x fastest (as
// `bspline::stencil_offsets`).
fn bspline_stencil_offset(n: u32) -> vec3<u32> {
    return vec3<u32>(n % 3u, (n / 3u) % 3u, n / 9u);
}
