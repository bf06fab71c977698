//! The look-up tables of SMAA's blending-weight pass, computed by the crate
//! at set-up rather than shipped as image files: the area table, the
//! diagonal table and the search table.
//!
//! # The area table
//!
//! The blending-weight pass reconstructs, for every edge segment it finds,
//! the silhouette line the aliased staircase stood for (the morphological
//! idea of MLAA, as SMAA refines it): a horizontal edge between a pixel row
//! (the pixel's own, "p's side") and the row across it ("the other side")
//! runs `start` pixels before the pixel and `end` pixels after it, and at
//! each of its two ends a *crossing edge* may leave it on p's side, on the
//! other side, on both or on neither. A crossing on one side means the
//! silhouette comes in from that side: the line is taken from the middle of
//! the crossing edge (half a pixel off the edge, on that side) to the middle
//! of the segment, where it meets the edge. Between that line and the edge
//! lies the part of a pixel that belongs to the row across: with a crossing
//! on p's side the pixel takes that much of the other side's colour; with
//! one on the other side, the pixel across takes that much of p's. An end
//! with no crossing, or with crossings on both sides (a junction, not a
//! step), adds nothing. The two ends add independently.
//!
//! Stored as RG8 (linear UNORM: the values are areas, never colours) in a
//! grid of 4 × 4 cells, one per pattern: cell column the start's crossing,
//! cell row the end's ([`Crossing`] in that order), each cell
//! [`MAX_DISTANCE`] × [`MAX_DISTANCE`] texels with the start distance along
//! x and the end distance along y, exactly (no compression: the pass
//! fetches a texel, no filtering). `.r` is what p takes from across the
//! edge, `.g` what the pixel across takes from p. A horizontal edge starts
//! at its left end; a vertical edge uses the same table with its top end as
//! the start and the pixel right of the edge as p.
//!
//! # The diagonal table
//!
//! A run of one-pixel steps along a diagonal is weighed as one line: see
//! [`DiagonalEnd`] for how the line is taken and [`diagonal_area`] for what
//! each cell gets. RG8 (linear UNORM), [`DIAGONAL_WIDTH`] ×
//! [`DIAGONAL_HEIGHT`]: 3 × 3 cells, one per pair of ends (cell column the
//! start's, row the end's, in [`DiagonalEnd`] order), each with the cells
//! before the pixel along x and after it along y.
//!
//! # The search table
//!
//! The pass walks along an edge two pixels per fetch: a bilinear fetch of
//! the edge texture a quarter of a pixel from the nearer pixel's centre
//! towards the farther one returns `0.75·near + 0.25·far` for both the edge
//! flag along the line and the crossing flag, so `round(4·v)` ∈ {0, 1, 3, 4}
//! tells both pixels apart. The search table turns the two rounded values
//! into how many of the two pixels the line still covers, and whether the
//! walk goes on; see [`search_step`]. R8, [`SEARCH_WIDTH`] × [`SEARCH_HEIGHT`]:
//! two 5 × 5 blocks (x: the crossing value, y: the edge value), one for
//! walks on which a pixel's crossing flag lies past it ([`Walk::ToStart`]:
//! left along a row, up along a column), one for walks on which it lies
//! before it ([`Walk::ToEnd`]: right, down): a pixel holds the flags of its
//! own left and top boundaries.

/// The distances (in pixels, 0 to `MAX_DISTANCE - 1`) one area cell holds
/// along each axis; longer distances are clamped to the last texel.
pub const MAX_DISTANCE: u32 = 64;

/// The area table's size in texels.
pub const AREA_WIDTH: u32 = 4 * MAX_DISTANCE;
/// The area table's size in texels.
pub const AREA_HEIGHT: u32 = 4 * MAX_DISTANCE;

/// The search table's size in texels.
pub const SEARCH_WIDTH: u32 = 10;
/// The search table's size in texels.
pub const SEARCH_HEIGHT: u32 = 5;

/// What crosses an edge segment at one of its ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    /// Nothing: the segment just stops.
    None = 0,
    /// An edge on the side of the pixel being weighed.
    PixelSide = 1,
    /// An edge on the side across the segment.
    OtherSide = 2,
    /// Edges on both sides: a junction.
    Both = 3,
}

impl Crossing {
    /// The four, in table order.
    pub const ALL: [Crossing; 4] = [
        Crossing::None,
        Crossing::PixelSide,
        Crossing::OtherSide,
        Crossing::Both,
    ];
}

/// The area between the edge and the line that runs from half a pixel off
/// the edge at one end (`x = 0`) to the edge at `x = half`, over the pixel
/// interval `[a, b]` (distances from that end).
fn wedge(half: f64, a: f64, b: f64) -> f64 {
    let (a, b) = (a.max(0.0), b.min(half));
    if b <= a {
        return 0.0;
    }
    // The line's distance from the edge is 0.5·(1 − x/half); integrate it.
    let height = |x: f64| 0.5 * (1.0 - x / half);
    0.5 * (height(a) + height(b)) * (b - a)
}

/// The areas (what p takes from across, what the pixel across takes from
/// p) for a pixel `start` pixels after the segment's start and `end`
/// pixels before its end, with crossings `at_start` and `at_end`.
pub fn orthogonal_area(at_start: Crossing, at_end: Crossing, start: u32, end: u32) -> (f64, f64) {
    let length = f64::from(start + end + 1);
    let half = 0.5 * length;
    let mut takes = (0.0, 0.0);
    // Each end reaches to the segment's middle, measured from that end.
    let from_start = wedge(half, f64::from(start), f64::from(start) + 1.0);
    let from_end = wedge(half, f64::from(end), f64::from(end) + 1.0);
    for (crossing, area) in [(at_start, from_start), (at_end, from_end)] {
        match crossing {
            Crossing::PixelSide => takes.0 += area,
            Crossing::OtherSide => takes.1 += area,
            Crossing::None | Crossing::Both => {}
        }
    }
    takes
}

/// An area as a UNORM byte.
fn unorm(v: f64) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The area table's bytes (RG8, row 0 first; see the [module
/// documentation](self)).
pub fn area_table() -> Vec<u8> {
    let mut bytes = vec![0u8; (AREA_WIDTH * AREA_HEIGHT * 2) as usize];
    for (column, &at_start) in Crossing::ALL.iter().enumerate() {
        for (row, &at_end) in Crossing::ALL.iter().enumerate() {
            for end in 0..MAX_DISTANCE {
                for start in 0..MAX_DISTANCE {
                    let (takes, given) = orthogonal_area(at_start, at_end, start, end);
                    let x = column as u32 * MAX_DISTANCE + start;
                    let y = row as u32 * MAX_DISTANCE + end;
                    let k = ((y * AREA_WIDTH + x) * 2) as usize;
                    bytes[k] = unorm(takes);
                    bytes[k + 1] = unorm(given);
                }
            }
        }
    }
    bytes
}

/// Which way a walk along an edge goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// Towards the start (left, down): a pixel's crossing flag lies on its
    /// far side from the walker (between it and the next pixel on).
    ToStart = 0,
    /// Towards the end (right, up): a pixel's crossing flag lies between it
    /// and the pixel before it.
    ToEnd = 1,
}

/// One step of a walk over the pair (`near`, `far`) of pixels: each has
/// its flag along the line (`edge`) and its crossing flag. The line covers
/// `near` when it has the edge (and, walking to the end, no crossing before
/// it); it covers `far` too when `far` has the edge and no crossing lies
/// between the two. Returns how many pixels it covers (0, 1 or 2) and
/// whether the walk goes on past `far`.
pub fn search_step(walk: Walk, near: (bool, bool), far: (bool, bool)) -> (u32, bool) {
    let ((near_edge, near_cross), (far_edge, far_cross)) = (near, far);
    match walk {
        Walk::ToStart => {
            if !near_edge {
                (0, false)
            } else if near_cross || !far_edge {
                (1, false)
            } else {
                (2, !far_cross)
            }
        }
        Walk::ToEnd => {
            if !near_edge || near_cross {
                (0, false)
            } else if far_cross || !far_edge {
                (1, false)
            } else {
                (2, true)
            }
        }
    }
}

/// How a search-table byte encodes a step: covered pixels, plus one when
/// the walk goes on, as thirds of 255.
fn encode_step((covered, go_on): (u32, bool)) -> u8 {
    (85 * (covered + u32::from(go_on))) as u8
}

/// The level `round(4·v)` of a bilinear fetch weighting near by 3/4 and
/// far by 1/4.
pub fn fetch_level(near: bool, far: bool) -> u32 {
    3 * u32::from(near) + u32::from(far)
}

/// The search table's bytes (R8, row 0 first; see the [module
/// documentation](self)). Levels 2 never occur and stay 0.
pub fn search_table() -> Vec<u8> {
    let mut bytes = vec![0u8; (SEARCH_WIDTH * SEARCH_HEIGHT) as usize];
    for walk in [Walk::ToStart, Walk::ToEnd] {
        for bits in 0..16u32 {
            let flag = |k: u32| bits & (1 << k) != 0;
            let near = (flag(0), flag(1));
            let far = (flag(2), flag(3));
            let x = walk as u32 * 5 + fetch_level(near.1, far.1);
            let y = fetch_level(near.0, far.0);
            bytes[(y * SEARCH_WIDTH + x) as usize] = encode_step(search_step(walk, near, far));
        }
    }
    bytes
}

/// The diagonal distances (in cells, 0 to `DIAGONAL_MAX_DISTANCE - 1`) one
/// diagonal cell holds along each axis.
pub const DIAGONAL_MAX_DISTANCE: u32 = 32;

/// The diagonal table's size in texels: 3 × 3 end patterns of
/// [`DIAGONAL_MAX_DISTANCE`] × [`DIAGONAL_MAX_DISTANCE`].
pub const DIAGONAL_WIDTH: u32 = 3 * DIAGONAL_MAX_DISTANCE;
/// The diagonal table's size in texels.
pub const DIAGONAL_HEIGHT: u32 = 3 * DIAGONAL_MAX_DISTANCE;

/// How a 45° staircase goes on past one end of a run of one-pixel steps.
///
/// A run is a row of *cells* along a diagonal, each a pixel with an edge
/// on its two boundaries that face the line (seen with the run rising to
/// the right: its left and top). In the middle the line is taken through
/// the steps' midpoints, half a pixel off each cell's corner, so each cell
/// gives the side across an eighth. A line a little flatter than 45° draws
/// runs of such steps joined by longer flat ones, and crosses each run from
/// near its first cell's upper-left corner to near its last cell's
/// upper-right one; so at an end that goes on flatter the line is taken
/// through that corner (for a steeper line, through the first cell's
/// lower-left corner and the corner a pixel above the last one's
/// upper-right), and between an end and the run's middle it moves linearly (the diagonal form of the orthogonal
/// lines' half-pixel offsets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiagonalEnd {
    /// The staircase stops, or goes on both ways: the line stays at the
    /// steps' midpoints.
    Straight = 0,
    /// It goes on along x: the line meets the first cell's upper-left
    /// corner at the start, the last cell's upper-right one at the end.
    Flatter = 1,
    /// It goes on along y: the line meets the first cell's lower-left
    /// corner at the start, the corner a pixel above the last cell's
    /// upper-right one at the end.
    Steeper = 2,
}

impl DiagonalEnd {
    /// The three, in table order.
    pub const ALL: [DiagonalEnd; 3] = [
        DiagonalEnd::Straight,
        DiagonalEnd::Flatter,
        DiagonalEnd::Steeper,
    ];

    /// The line's offset above the cells' lower-left corners at this end
    /// (`y = x + offset` in the run's frame, cell `k` spanning `[k, k+1]²`),
    /// at the run's start or its end.
    fn offset(self, at_start: bool) -> f64 {
        match (self, at_start) {
            (DiagonalEnd::Straight, _) => 0.5,
            (DiagonalEnd::Flatter, true) | (DiagonalEnd::Steeper, false) => 1.0,
            (DiagonalEnd::Flatter, false) | (DiagonalEnd::Steeper, true) => 0.0,
        }
    }
}

/// ∫ max(0, h) over `[a, b]` for `h` linear from `ha` to `hb`.
fn positive_part(a: f64, b: f64, ha: f64, hb: f64) -> f64 {
    let w = b - a;
    if w <= 0.0 {
        return 0.0;
    }
    match (ha >= 0.0, hb >= 0.0) {
        (true, true) => 0.5 * (ha + hb) * w,
        (false, false) => 0.0,
        (true, false) => 0.5 * ha * ha / (ha - hb) * w,
        (false, true) => 0.5 * hb * hb / (hb - ha) * w,
    }
}

/// The areas of cell `back` of a run with `back` cells before it and
/// `forward` after it: what the cell takes from across its top edge (the
/// part of it above the line) and what the pixel above takes from it (the
/// part of that pixel below the line), in the run's frame (rising to the
/// right; a falling run is this one mirrored).
pub fn diagonal_area(
    at_start: DiagonalEnd,
    at_end: DiagonalEnd,
    back: u32,
    forward: u32,
) -> (f64, f64) {
    let n = f64::from(back + forward + 1);
    let k = f64::from(back);
    let middle = 0.5 * n;
    // The line's offset: from the start's to 1/2 at the middle, then to the end's.
    let (first, last) = (at_start.offset(true), at_end.offset(false));
    let offset = |x: f64| {
        if x <= middle {
            first + (0.5 - first) * (x / middle)
        } else {
            0.5 + (last - 0.5) * ((x - middle) / middle)
        }
    };
    // Over the cell's column, split where the offset has its kink.
    let mut points = vec![k, k + 1.0];
    if middle > k && middle < k + 1.0 {
        points.insert(1, middle);
    }
    let (mut takes, mut given) = (0.0, 0.0);
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        // The line's height above the cell's top edge (y = k + 1).
        let above = |x: f64| x + offset(x) - (k + 1.0);
        takes += positive_part(a, b, -above(a), -above(b));
        given += positive_part(a, b, above(a), above(b));
    }
    (takes, given)
}

/// The diagonal table's bytes (RG8, row 0 first): cell column the start's
/// [`DiagonalEnd`], cell row the end's, each cell the cells before (x) and
/// after (y); `.r`, `.g` as [`diagonal_area`] gives them.
pub fn diagonal_table() -> Vec<u8> {
    let mut bytes = vec![0u8; (DIAGONAL_WIDTH * DIAGONAL_HEIGHT * 2) as usize];
    for (column, &at_start) in DiagonalEnd::ALL.iter().enumerate() {
        for (row, &at_end) in DiagonalEnd::ALL.iter().enumerate() {
            for forward in 0..DIAGONAL_MAX_DISTANCE {
                for back in 0..DIAGONAL_MAX_DISTANCE {
                    let (takes, given) = diagonal_area(at_start, at_end, back, forward);
                    let x = column as u32 * DIAGONAL_MAX_DISTANCE + back;
                    let y = row as u32 * DIAGONAL_MAX_DISTANCE + forward;
                    let k = ((y * DIAGONAL_WIDTH + x) * 2) as usize;
                    bytes[k] = unorm(takes);
                    bytes[k + 1] = unorm(given);
                }
            }
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f64 = 1e-12;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < EPS
    }

    /// The share of the cell `[k, k+1]²` above `line` and of the pixel
    /// above it below `line`, by 512 × 512 sub-samples.
    fn sampled(line: &dyn Fn(f64) -> f64, k: f64) -> (f64, f64) {
        let n = 512;
        let (mut above, mut below) = (0u32, 0u32);
        for i in 0..n {
            let x = k + (f64::from(i) + 0.5) / f64::from(n);
            for j in 0..n {
                let y = (f64::from(j) + 0.5) / f64::from(n);
                if k + y > line(x) {
                    above += 1;
                }
                if k + 1.0 + y < line(x) {
                    below += 1;
                }
            }
        }
        let all = f64::from(n * n);
        (f64::from(above) / all, f64::from(below) / all)
    }

    #[test]
    fn diagonal_runs_give_the_areas_of_their_lines() {
        // Straight ends: the line through the steps' midpoints, an eighth
        // each way in every cell.
        for back in 0..10 {
            for forward in 0..10 {
                let (t, g) =
                    diagonal_area(DiagonalEnd::Straight, DiagonalEnd::Straight, back, forward);
                assert!(
                    close(t, 0.125) && close(g, 0.125),
                    "{back} {forward}: {t} {g}"
                );
            }
        }
        // Steeper past both ends: one straight line from the first cell's
        // lower-left corner to a pixel above the last one's upper-right,
        // slope 1 + 1/n; flatter past both, from the first's upper-left to
        // the last's upper-right, slope 1 - 1/n.
        for n in 2..12u32 {
            let l = f64::from(n);
            let steeper = move |x: f64| x * (1.0 + 1.0 / l);
            let flatter = move |x: f64| 1.0 + x * (1.0 - 1.0 / l);
            let lines: [(DiagonalEnd, &dyn Fn(f64) -> f64); 2] = [
                (DiagonalEnd::Steeper, &steeper),
                (DiagonalEnd::Flatter, &flatter),
            ];
            for (end, line) in lines {
                for back in 0..n {
                    let (t, g) = diagonal_area(end, end, back, n - 1 - back);
                    let (st, sg) = sampled(line, f64::from(back));
                    assert!(
                        (t - st).abs() < 2e-3 && (g - sg).abs() < 2e-3,
                        "{end:?} {n} {back}: {t} {st} / {g} {sg}"
                    );
                }
            }
        }
        // A run turned a half turn is the run read from its other end,
        // with its sides swapped (flatter stays flatter).
        for &a in &DiagonalEnd::ALL {
            for &b in &DiagonalEnd::ALL {
                for back in 0..12 {
                    for forward in 0..12 {
                        let (t, g) = diagonal_area(a, b, back, forward);
                        let (t2, g2) = diagonal_area(b, a, forward, back);
                        assert!(close(t, g2) && close(g, t2), "{a:?} {b:?} {back} {forward}");
                    }
                }
            }
        }
        let t = diagonal_table();
        let (takes, given) = diagonal_area(DiagonalEnd::Flatter, DiagonalEnd::Steeper, 3, 5);
        let k = (((2 * DIAGONAL_MAX_DISTANCE + 5) * DIAGONAL_WIDTH + DIAGONAL_MAX_DISTANCE + 3) * 2)
            as usize;
        assert_eq!((t[k], t[k + 1]), (unorm(takes), unorm(given)));
    }

    #[test]
    fn a_z_step_gives_the_trapezoids_of_its_straight_line() {
        // A Z step: the silhouette comes in on p's side at the start and
        // leaves on the other side at the end, so its line is one straight
        // line from half a pixel below the edge at x = 0 to half a pixel
        // above at x = L, slope 1/L. A pixel wholly before the middle takes
        // the trapezoid between that line and the edge: its mean height
        // (the line's depth at the pixel's centre) times its width.
        for length in 1..40u32 {
            let l = f64::from(length);
            for start in 0..length {
                let end = length - 1 - start;
                let (takes, given) =
                    orthogonal_area(Crossing::PixelSide, Crossing::OtherSide, start, end);
                let centre = f64::from(start) + 0.5;
                let depth = |x: f64| 0.5 - x / l; // below the edge for x < L/2
                if f64::from(start) + 1.0 <= l / 2.0 {
                    assert!(close(takes, depth(centre)), "{length} {start}: {takes}");
                    assert!(close(given, 0.0));
                } else if f64::from(start) >= l / 2.0 {
                    assert!(close(given, -depth(centre)), "{length} {start}: {given}");
                    assert!(close(takes, 0.0));
                } else {
                    // The pixel the line crosses: a triangle each side.
                    let left = l / 2.0 - f64::from(start);
                    let right = f64::from(start) + 1.0 - l / 2.0;
                    assert!(close(takes, 0.5 * left * left / l), "{length} {start}");
                    assert!(close(given, 0.5 * right * right / l), "{length} {start}");
                }
            }
        }
    }

    #[test]
    fn over_a_whole_step_the_areas_add_up_to_the_triangles() {
        // The line of each end encloses a triangle of base L/2 and height
        // 1/2 with the edge: the pixels' areas sum to L/8 per crossing.
        for length in 1..50u32 {
            for (a, b) in [
                (Crossing::PixelSide, Crossing::PixelSide),
                (Crossing::PixelSide, Crossing::OtherSide),
                (Crossing::OtherSide, Crossing::None),
            ] {
                let (mut takes, mut given) = (0.0, 0.0);
                for start in 0..length {
                    let (t, g) = orthogonal_area(a, b, start, length - 1 - start);
                    takes += t;
                    given += g;
                }
                let count = |side| f64::from(u8::from(a == side) + u8::from(b == side));
                let l = f64::from(length);
                assert!(close(takes, count(Crossing::PixelSide) * l / 8.0));
                assert!(close(given, count(Crossing::OtherSide) * l / 8.0));
            }
        }
    }

    #[test]
    fn mirrored_patterns_give_mirrored_areas() {
        for &a in &Crossing::ALL {
            for &b in &Crossing::ALL {
                for start in 0..20 {
                    for end in 0..20 {
                        let (t, g) = orthogonal_area(a, b, start, end);
                        // Read from the other end.
                        assert_eq!((t, g), orthogonal_area(b, a, end, start));
                        // Seen from across the edge, the sides swap.
                        let swap = |c| match c {
                            Crossing::PixelSide => Crossing::OtherSide,
                            Crossing::OtherSide => Crossing::PixelSide,
                            c => c,
                        };
                        assert_eq!((g, t), orthogonal_area(swap(a), swap(b), start, end));
                        // The ends add independently.
                        let (t1, g1) = orthogonal_area(a, Crossing::None, start, end);
                        let (t2, g2) = orthogonal_area(Crossing::None, b, start, end);
                        assert!(close(t, t1 + t2) && close(g, g1 + g2));
                    }
                }
            }
        }
        for start in 0..10 {
            for end in 0..10 {
                for c in [Crossing::None, Crossing::Both] {
                    assert_eq!(orthogonal_area(c, c, start, end), (0.0, 0.0));
                }
            }
        }
        // A U of three pixels, by hand: the middle pixel straddles both
        // halves; the first takes the trapezoid of depths 1/2 .. 1/6.
        let (t, _) = orthogonal_area(Crossing::PixelSide, Crossing::PixelSide, 0, 2);
        assert!(close(t, 0.5 * (0.5 + 0.5 / 3.0)));
        let (t, _) = orthogonal_area(Crossing::PixelSide, Crossing::PixelSide, 1, 1);
        assert!(close(t, 2.0 * 0.5 * 0.5 * (0.5 / 3.0)));
    }

    #[test]
    fn the_area_table_holds_the_areas_as_bytes() {
        let t = area_table();
        assert_eq!(t.len(), (AREA_WIDTH * AREA_HEIGHT * 2) as usize);
        for (column, &a) in Crossing::ALL.iter().enumerate() {
            for (row, &b) in Crossing::ALL.iter().enumerate() {
                for (start, end) in [(0, 0), (3, 7), (63, 1), (10, 10)] {
                    let x = column as u32 * MAX_DISTANCE + start;
                    let y = row as u32 * MAX_DISTANCE + end;
                    let k = ((y * AREA_WIDTH + x) * 2) as usize;
                    let (takes, given) = orthogonal_area(a, b, start, end);
                    assert_eq!(t[k], (takes * 255.0).round() as u8);
                    assert_eq!(t[k + 1], (given * 255.0).round() as u8);
                }
            }
        }
        // The L of a one-pixel segment: the pixel takes 1/8 + 0 ≈ 32/255.
        let k = ((MAX_DISTANCE) * 2) as usize; // column PixelSide, row None, (0, 0)
        assert_eq!(t[k], 32);
    }

    /// Walk a row of (edge, crossing) flags the slow way: the line's extent
    /// towards the start from pixel `at` (which has the edge), where the
    /// crossing flag of pixel `k` lies between `k − 1` and `k`.
    fn brute_to_start(row: &[(bool, bool)], at: usize) -> usize {
        let mut d = 0;
        // The line continues from `k` to `k − 1` when `k` has no crossing
        // and `k − 1` has the edge.
        while at > d && !row[at - d].1 && row[at - d - 1].0 {
            d += 1;
        }
        d
    }

    fn brute_to_end(row: &[(bool, bool)], at: usize) -> usize {
        let mut d = 0;
        while at + d + 1 < row.len() && row[at + d + 1].0 && !row[at + d + 1].1 {
            d += 1;
        }
        d
    }

    /// The pass's walk, with the table: pairs of pixels per step.
    fn table_walk(row: &[(bool, bool)], at: usize, walk: Walk) -> usize {
        let table = search_table();
        let flag = |k: isize| -> (bool, bool) {
            usize::try_from(k)
                .ok()
                .and_then(|k| row.get(k).copied())
                .unwrap_or((false, false))
        };
        let dir: isize = if walk == Walk::ToStart { -1 } else { 1 };
        if walk == Walk::ToStart && row[at].1 {
            return 0;
        }
        let mut d = 0;
        loop {
            let near = flag(at as isize + dir * (d as isize + 1));
            let far = flag(at as isize + dir * (d as isize + 2));
            let x = walk as u32 * 5 + fetch_level(near.1, far.1);
            let y = fetch_level(near.0, far.0);
            let v = u32::from(table[(y * SEARCH_WIDTH + x) as usize]) / 85;
            let (covered, go_on) = (v.min(2) as usize, v == 3);
            d += covered;
            if !go_on {
                return d;
            }
        }
    }

    #[test]
    fn the_search_table_walks_as_far_as_a_pixel_by_pixel_walk() {
        // Every row of 9 pixels (the middle one on the edge): 4^8 rows.
        for bits in 0..(1u32 << 16) {
            let mut row: Vec<(bool, bool)> = (0..8)
                .map(|k| (bits >> (2 * k) & 1 != 0, bits >> (2 * k + 1) & 1 != 0))
                .collect();
            row.insert(4, (true, bits & 1 != 0));
            assert_eq!(
                table_walk(&row, 4, Walk::ToStart),
                brute_to_start(&row, 4),
                "{row:?}"
            );
            assert_eq!(
                table_walk(&row, 4, Walk::ToEnd),
                brute_to_end(&row, 4),
                "{row:?}"
            );
        }
    }
}
