//! How the visibility buffer stores a sample's (instance id, triangle id) in one `R32_UINT`
//! word (seed `003` packs its draw and primitive ids the same way): the triangle in the low
//! bits, as many as the scene's largest mesh needs, the instance above them. A scene that
//! needs more than 32 bits is refused with the pass's name; `R32G32_UINT` holds any scene.

/// Low bits that hold the triangle id in a scene whose largest mesh has `max_triangles`, when
/// the instance id fits the bits above them; otherwise why not.
pub fn triangle_bits(instances: u32, max_triangles: u32) -> Result<u32, String> {
    let bits = |n: u32| 32 - n.saturating_sub(1).leading_zeros();
    let (triangle, instance) = (bits(max_triangles), bits(instances));
    // The shaders shift by the triangle bits, so 32 of them (one instance) are refused too.
    if triangle + instance > 32 || triangle == 32 {
        return Err(format!(
            "R32_UINT visibility ids hold instance and triangle ids in 32 bits; this scene needs {instance} + {triangle} \
             ({instances} instances, up to {max_triangles} triangles per mesh): use R32G32_UINT"
        ));
    }
    Ok(triangle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_triangle_takes_the_bits_its_largest_mesh_needs() {
        assert_eq!(triangle_bits(1, 1), Ok(0));
        assert_eq!(triangle_bits(10_000, 320), Ok(9));
        assert_eq!(triangle_bits(81, 8360), Ok(14));
        assert_eq!(triangle_bits(1 << 20, 4096), Ok(12));
        assert_eq!(triangle_bits(2, 1 << 31), Ok(31));
        assert!(triangle_bits(1, u32::MAX).is_err());
        let refused = triangle_bits((1 << 20) + 1, 4097).unwrap_err();
        assert!(refused.contains("21 + 13") && refused.contains("R32G32_UINT"), "{refused}");
    }
}
