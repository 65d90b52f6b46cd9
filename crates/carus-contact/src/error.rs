//! Errors of the contact crate: each names the offending item and the fix.

/// What went wrong building a collider, a body or a contact law.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    #[error("the {what} surface has no triangles: pass a closed triangle surface")]
    EmptySurface { what: &'static str },
    #[error("vertex {vertex} of the {what} surface has a non-finite coordinate")]
    NonFiniteVertex { what: &'static str, vertex: usize },
    #[error("triangle {triangle} of the {what} surface refers to vertex {vertex}, but there are only {count} vertices")]
    VertexOutOfRange { what: &'static str, triangle: usize, vertex: u32, count: usize },
    #[error("triangle {triangle} of the {what} surface has zero area: remove it or merge its vertices")]
    DegenerateTriangle { what: &'static str, triangle: usize },
    #[error("the {what} region table has {labels} labels but the surface has {triangles} triangles: give one label per triangle")]
    RegionTableLength { what: &'static str, labels: usize, triangles: usize },
    #[error("region label {label} on triangle {triangle} has no name (only {names} region names given)")]
    RegionLabelOutOfRange { triangle: usize, label: u16, names: usize },
    #[error("parameter `{name}` = {value} is invalid: {hint}")]
    InvalidParameter { name: &'static str, value: f64, hint: &'static str },
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch { what: &'static str, expected: usize, got: usize },
    #[error("body {body} does not exist (the set has {count} bodies)")]
    NoSuchBody { body: usize, count: usize },
}

/// Checks that a named parameter is finite and positive (or zero when `allow_zero`).
pub(crate) fn check_non_negative(
    name: &'static str,
    value: f64,
    allow_zero: bool,
) -> Result<f64, ContactError> {
    let ok = value.is_finite() && (value > 0.0 || (allow_zero && value == 0.0));
    if ok {
        Ok(value)
    } else if allow_zero {
        Err(ContactError::InvalidParameter { name, value, hint: "must be finite and zero or positive" })
    } else {
        Err(ContactError::InvalidParameter { name, value, hint: "must be finite and positive" })
    }
}
