// Lit triangle meshes: Lambert key + fill + headlight, ambient and a rim
// term, in linear light (the sRGB target encodes the result).

// True when the colour target is not an sRGB format, so the hardware will
// not encode linear light: the shader does it (egui's window surfaces).
override encode_srgb: bool = false;

struct Frame {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // Lights in camera space: xyz towards the light (unit), w intensity.
    key: vec4<f32>,
    fill: vec4<f32>,
    // x headlight, y ambient, z rim, w 1 for perspective and 0 for orthographic.
    shading: vec4<f32>,
};

struct Material {
    // Linear RGB and opacity.
    colour: vec4<f32>,
    // x, y: scalar mapped to the ends of the colour map; z: 1 when the
    // scalar field is used; w: v coordinate of the colour map's row.
    scalar: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var colour_maps: texture_2d<f32>;
@group(0) @binding(2) var colour_map_sampler: sampler;
@group(1) @binding(0) var<uniform> material: Material;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) view_position: vec3<f32>,
    @location(2) scalar: f32,
};

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) scalar: f32,
) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    // The view transform is rigid, so it carries normals unchanged in length.
    out.normal = (frame.view * vec4<f32>(normal, 0.0)).xyz;
    out.view_position = (frame.view * vec4<f32>(position, 1.0)).xyz;
    out.scalar = scalar;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // Back faces of open meshes are lit as if seen from their own side.
    var n = normalize(in.normal);
    if (!front) {
        n = -n;
    }
    var to_eye = vec3<f32>(0.0, 0.0, 1.0);
    if (frame.shading.w > 0.5) {
        to_eye = normalize(-in.view_position);
    }

    var base = material.colour.rgb;
    if (material.scalar.z > 0.5) {
        let span = material.scalar.y - material.scalar.x;
        let t = clamp((in.scalar - material.scalar.x) / span, 0.0, 1.0);
        base = textureSampleLevel(colour_maps, colour_map_sampler, vec2<f32>(t, material.scalar.w), 0.0).rgb;
    }

    let facing = max(dot(n, to_eye), 0.0);
    let diffuse = frame.shading.y
        + frame.key.w * max(dot(n, frame.key.xyz), 0.0)
        + frame.fill.w * max(dot(n, frame.fill.xyz), 0.0)
        + frame.shading.x * facing;
    let rim = frame.shading.z * pow(1.0 - facing, 3.0);
    let lit = base * diffuse + rim * mix(base, vec3<f32>(1.0), 0.5);
    if (encode_srgb) {
        return vec4<f32>(linear_to_srgb(lit), material.colour.a);
    }
    return vec4<f32>(lit, material.colour.a);
}

// IEC 61966-2-1, as colour.rs.
fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, x * 12.92, x <= vec3<f32>(0.0031308));
}
