//! Knit patterns: which yarn each spring belongs to, and the point classes that follow.
//!
//! Sakaguchi & Miyata §4 (Fig. 6): looking at the yarn kinds of the four springs that leave a mass
//! point (left, right, down, up), an alternately knitted (交編) fabric has exactly four kinds of
//! point, numbered 1–4, and tiling them builds the fabric. We model the cause rather than the
//! effect: every spring gets a yarn kind from a small periodic [`Tile`], and a point's class is
//! derived from the kinds of its four springs.

use serde::{Deserialize, Serialize};

use crate::base::{Direction, YarnKind};

/// The knit patterns a scene can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Pattern {
    /// Plain knit with a single (nylon) yarn: every spring is nylon, every point class 1.
    Plain,
    /// 交編: nylon and support yarn knitted in alternate courses, as in the paper (Fig. 2b, 3).
    #[default]
    Alternating,
}

/// A periodic tile of yarn kinds, `width` wales × `height` courses.
///
/// Cell `(w, c)` holds the kind of the course spring leaving point `(w, c)` towards `w + 1` and the
/// kind of the wale spring leaving it towards `c + 1`. Point `(w, c)` of the fabric uses cell
/// `(w mod width, c mod height)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tile {
    width: usize,
    height: usize,
    /// Row-major (`c * width + w`): kind of the course spring to the right of each cell.
    course: Vec<YarnKind>,
    /// Row-major: kind of the wale spring above each cell.
    wale: Vec<YarnKind>,
}

impl Tile {
    /// The tile of a pattern.
    ///
    /// `Alternating`: courses alternate nylon / support (each course is one yarn, so all its course
    /// springs share that yarn); the loop legs joining two courses alternate in a checkerboard,
    /// `(w + c) mod 2`, because neighbouring loops of a course are pulled through loops of the two
    /// different yarns. With courses alternating too, this gives the paper's four point classes.
    pub fn of(pattern: Pattern) -> Tile {
        match pattern {
            Pattern::Plain => Tile {
                width: 1,
                height: 1,
                course: vec![YarnKind::Nylon],
                wale: vec![YarnKind::Nylon],
            },
            Pattern::Alternating => {
                let kind = |i: usize| YarnKind::KNITTED[i % 2];
                let (width, height) = (2, 2);
                let mut course = Vec::new();
                let mut wale = Vec::new();
                for c in 0..height {
                    for w in 0..width {
                        course.push(kind(c));
                        wale.push(kind(w + c));
                    }
                }
                Tile {
                    width,
                    height,
                    course,
                    wale,
                }
            }
        }
    }

    /// Tile size as (wales, courses).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn cell(&self, wale: isize, course: isize) -> usize {
        let w = wale.rem_euclid(self.width as isize) as usize;
        let c = course.rem_euclid(self.height as isize) as usize;
        c * self.width + w
    }

    /// Yarn kind of the spring leaving point `(wale, course)` in `direction` (towards +1).
    /// Coordinates may be negative: the tile is periodic.
    pub fn spring_kind(&self, wale: isize, course: isize, direction: Direction) -> YarnKind {
        let cell = self.cell(wale, course);
        match direction {
            Direction::Course => self.course[cell],
            Direction::Wale => self.wale[cell],
        }
    }

    /// Kinds of the four springs around point `(wale, course)`: `[left, right, down, up]`.
    pub fn point_springs(&self, wale: isize, course: isize) -> [YarnKind; 4] {
        [
            self.spring_kind(wale - 1, course, Direction::Course),
            self.spring_kind(wale, course, Direction::Course),
            self.spring_kind(wale, course - 1, Direction::Wale),
            self.spring_kind(wale, course, Direction::Wale),
        ]
    }

    /// The class (1-based) of point `(wale, course)`: distinct `[left, right, down, up]` spring
    /// combinations are numbered in the order they first appear when the tile is read row by row.
    pub fn point_class(&self, wale: isize, course: isize) -> u8 {
        let target = self.point_springs(wale, course);
        let mut seen: Vec<[YarnKind; 4]> = Vec::new();
        for c in 0..self.height as isize {
            for w in 0..self.width as isize {
                let springs = self.point_springs(w, c);
                if !seen.contains(&springs) {
                    seen.push(springs);
                }
                if springs == target {
                    // Pushed just above when it was new, so it is in `seen`.
                    return seen.iter().position(|s| *s == target).unwrap() as u8 + 1;
                }
            }
        }
        unreachable!("every point's springs appear in its own tile")
    }

    /// The yarn of the course through point `(wale, course)`: the kind of its course springs.
    pub fn course_yarn(&self, wale: isize, course: isize) -> YarnKind {
        self.spring_kind(wale, course, Direction::Course)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_pattern_has_one_class_and_one_yarn() {
        let tile = Tile::of(Pattern::Plain);
        for c in -3..3 {
            for w in -3..3 {
                assert_eq!(tile.point_class(w, c), 1);
                assert_eq!(tile.point_springs(w, c), [YarnKind::Nylon; 4]);
            }
        }
    }

    #[test]
    fn alternating_pattern_has_the_papers_four_classes_tiled_2x2() {
        let tile = Tile::of(Pattern::Alternating);
        let mut classes = std::collections::BTreeSet::new();
        for c in -4..4 {
            for w in -4..4 {
                let class = tile.point_class(w, c);
                classes.insert(class);
                assert_eq!(
                    class,
                    tile.point_class(w + 2, c),
                    "periodic along the course"
                );
                assert_eq!(class, tile.point_class(w, c + 2), "periodic along the wale");
                let [left, right, _, _] = tile.point_springs(w, c);
                assert_eq!(left, right, "a course is one yarn");
            }
        }
        assert_eq!(classes.into_iter().collect::<Vec<_>>(), vec![1, 2, 3, 4]);
        // Courses alternate yarns.
        assert_ne!(tile.course_yarn(0, 0), tile.course_yarn(0, 1));
        // The class of a point is determined by its springs, and distinct classes have distinct springs.
        assert_ne!(tile.point_springs(0, 0), tile.point_springs(1, 0));
        assert_ne!(tile.point_springs(0, 0), tile.point_springs(0, 1));
    }
}
