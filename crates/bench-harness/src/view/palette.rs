//! Colours of material pairs, one table for the page (`surftrack view`) and the report
//! pictures, so an interface has the same colour in both.
//!
//! The outer surface of material `m` (pair `{0, m}`) takes the `m`-th base colour; a wall
//! between two materials `{a, b}` (both non-zero) the mean of their base colours, so the
//! wall between a blue and an orange bubble reads as "between blue and orange". The base
//! colours are saturated and of distinct hue (no grey): a shaded pixel keeps its colour's
//! chromaticity, which is how the tests tell materials apart on screen and in pictures.

/// Base colours (sRGB) of materials 1, 2, …; material `m` takes entry `(m − 1) mod 10`.
pub const MATERIAL_COLOURS: [[u8; 3]; 10] = [
    [31, 119, 180],  // blue
    [255, 127, 14],  // orange
    [44, 160, 44],   // green
    [214, 39, 40],   // red
    [148, 103, 189], // purple
    [23, 190, 207],  // cyan
    [227, 119, 194], // pink
    [188, 189, 34],  // olive
    [140, 86, 75],   // brown
    [255, 215, 0],   // gold
];

/// The colour of material `m` alone (label 0, the outside, is a light grey).
pub fn material_colour(m: u32) -> [u8; 3] {
    if m == 0 {
        return [200, 200, 200];
    }
    MATERIAL_COLOURS[((m - 1) % MATERIAL_COLOURS.len() as u32) as usize]
}

/// The colour of the interface between materials `a` and `b`, whichever side is front.
pub fn pair_colour(a: u32, b: u32) -> [u8; 3] {
    let (lo, hi) = (a.min(b), a.max(b));
    if lo == 0 {
        return material_colour(hi);
    }
    let (p, q) = (material_colour(lo), material_colour(hi));
    [0, 1, 2].map(|i| ((u16::from(p[i]) + u16::from(q[i])) / 2) as u8)
}

/// `#rrggbb` of a colour, for the page and its legend.
pub fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_are_unordered_and_outer_surfaces_take_the_material_colour() {
        assert_eq!(pair_colour(1, 0), pair_colour(0, 1));
        assert_eq!(pair_colour(0, 2), material_colour(2));
        assert_eq!(pair_colour(2, 1), [143, 123, 97]);
        assert_ne!(pair_colour(0, 1), pair_colour(0, 2));
        assert_eq!(material_colour(11), material_colour(1));
        assert_eq!(hex([31, 119, 180]), "#1f77b4");
    }
}
