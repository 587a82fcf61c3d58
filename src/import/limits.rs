//! Documented limits on imported numbers. Every number that enters from a
//! URDF or a mesh is checked here before it reaches geometry code (parry's
//! voxelizer and convex hull assume finite, moderately sized inputs and
//! panic otherwise), so bad input is an error naming the file and element.

/// Largest coordinate, primitive dimension or joint offset accepted (m).
/// Robots and their surroundings are far smaller; beyond this, products of
/// coordinates (volumes, second moments) lose all precision or overflow.
pub const MAX_COORDINATE: f64 = 1.0e4;

/// Smallest primitive dimension accepted (m): 1 µm. Below it a box or
/// cylinder is flat at the precision hull construction works at.
pub const MIN_DIMENSION: f64 = 1.0e-6;

/// Most vertices one mesh file may produce (5 million: about 120 MB of
/// positions). A COLLADA scene that instances its geometry many times could
/// otherwise multiply a small file into an unbounded mesh.
pub const MAX_MESH_VERTICES: usize = 5_000_000;

/// Checks that every value is finite and at most [`MAX_COORDINATE`] in
/// magnitude; `what` names the quantity in the message.
pub fn check_coordinates(what: &str, values: &[f64]) -> Result<(), String> {
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(format!("{what}: {v} is not a finite number"));
    }
    if let Some(v) = values.iter().find(|v| v.abs() > MAX_COORDINATE) {
        return Err(format!(
            "{what}: {v:e} exceeds the largest accepted magnitude {MAX_COORDINATE:e} m"
        ));
    }
    Ok(())
}

/// Checks an input mass (kg): finite and non-negative (a zero mass is a
/// massless link, which the importer reports and gives a density mass).
pub fn check_mass(m: f64) -> Result<(), String> {
    if !m.is_finite() || m < 0.0 {
        return Err(format!(
            "inertial mass {m} must be a finite, non-negative number (kg)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_reject_non_finite_and_huge_values_and_accept_ordinary_ones() {
        assert!(check_coordinates("x", &[0.0, -1.5, 1e3]).is_ok());
        for bad in [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e308, -2e4] {
            let e = check_coordinates("origin xyz", &[0.0, bad]).unwrap_err();
            assert!(e.starts_with("origin xyz: "), "{e}");
        }
        assert!(check_mass(0.0).is_ok() && check_mass(2.5).is_ok());
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            assert!(check_mass(bad).is_err());
        }
    }
}
