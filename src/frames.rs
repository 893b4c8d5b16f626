//! Frame sets: which frames of a scene a render writes (`--frames`), and one render-farm
//! task's share of them (`--chunk`).
//!
//! Two syntaxes are accepted. This program's own, `A..B` (B exclusive, as Rust ranges),
//! `A..`, `..B`, and the one the render managers use (Open Job Description's range
//! expression, which Deadline writes): a comma-separated list of `N`, `A-B` and `A-B:S`,
//! inclusive at both ends, `S` a non-zero step (negative for a range counting down). A
//! single frame `N` means the same in both. `0..10` and `0-9` are the same ten frames.
//!
//! A set is kept as its sorted, distinct frames: a farm task's list is short (the scene's
//! frames at most), and the renderer walks it in order.

use std::fmt;
use std::ops::Range;

/// A `--frames` value that does not name frames of the scene; its message names the value,
/// the part that is wrong and what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--frames {spec:?}: {reason}")]
pub struct FrameSpecError {
    spec: String,
    reason: String,
}

/// Distinct frames in increasing order (possibly none: a farm task past the last chunk).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameSet {
    frames: Vec<u32>,
}

impl FrameSet {
    /// Every frame of a scene of `count` frames.
    pub fn all(count: u32) -> FrameSet {
        FrameSet::from(0..count)
    }

    /// `--frames SPEC` against a scene of `count` frames (`None`: all of them).
    pub fn parse(spec: Option<&str>, count: u32) -> Result<FrameSet, FrameSpecError> {
        let Some(spec) = spec else {
            return Ok(FrameSet::all(count));
        };
        let fail = |reason: String| FrameSpecError {
            spec: spec.to_string(),
            reason,
        };
        if spec.trim().is_empty() {
            return Err(fail(format!("no frames given; expected {EXAMPLES}")));
        }
        if spec.contains("..") {
            return exclusive_range(spec, count).map_err(fail);
        }
        list(spec, count).map_err(fail)
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        self.frames.iter().copied()
    }

    pub fn contains(&self, frame: u32) -> bool {
        self.frames.binary_search(&frame).is_ok()
    }

    pub fn first(&self) -> Option<u32> {
        self.frames.first().copied()
    }

    pub fn last(&self) -> Option<u32> {
        self.frames.last().copied()
    }

    /// From the first frame to one past the last (empty for an empty set).
    pub fn span(&self) -> Range<u32> {
        match (self.first(), self.last()) {
            (Some(a), Some(b)) => a..b + 1,
            _ => 0..0,
        }
    }

    /// The set as one half-open range, when it has no gaps.
    pub fn as_range(&self) -> Option<Range<u32>> {
        let span = self.span();
        (span.len() == self.len()).then_some(span)
    }

    /// How many chunks of `size` frames the set makes (the last may be shorter).
    pub fn chunk_count(&self, size: u32) -> usize {
        self.len().div_ceil(size.max(1) as usize)
    }

    /// Chunk `index` (0-based): frames `index·size ..` of the sorted set, at most `size` of
    /// them; `None` past the last chunk.
    pub fn chunk(&self, size: u32, index: u32) -> Option<FrameSet> {
        let size = size.max(1) as usize;
        let start = (index as usize).checked_mul(size)?;
        if start >= self.len() {
            return None;
        }
        let end = start.saturating_add(size).min(self.len());
        Some(FrameSet {
            frames: self.frames[start..end].to_vec(),
        })
    }
}

impl From<Range<u32>> for FrameSet {
    fn from(r: Range<u32>) -> FrameSet {
        FrameSet {
            frames: r.collect(),
        }
    }
}

/// The set in the render managers' syntax (inclusive), runs of equal steps folded:
/// `1-3,5-19:2`. This is what notes, error messages and manifests show.
impl fmt::Display for FrameSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = &self.frames;
        let mut i = 0;
        let mut sep = "";
        while i < v.len() {
            let (len, step) = run_at(v, i);
            match (len, step) {
                (1, _) => write!(f, "{sep}{}", v[i])?,
                (_, 1) => write!(f, "{sep}{}-{}", v[i], v[i + len - 1])?,
                _ => write!(f, "{sep}{}-{}:{step}", v[i], v[i + len - 1])?,
            }
            sep = ",";
            i += len;
        }
        Ok(())
    }
}

/// The run of equal steps starting at `v[i]`: its length and step. Two frames a step
/// apart only count as a run for step 1 (`4-5`); otherwise `4,7` reads better than
/// `4-7:3`, and the second frame may start a longer run of its own.
fn run_at(v: &[u32], i: usize) -> (usize, u32) {
    let Some(&next) = v.get(i + 1) else {
        return (1, 1);
    };
    let step = next - v[i];
    let mut len = 2;
    while v.get(i + len).is_some_and(|&x| x - v[i + len - 1] == step) {
        len += 1;
    }
    if len == 2 && step != 1 {
        (1, 1)
    } else {
        (len, step)
    }
}

/// What a valid `--frames` value looks like, for error messages.
const EXAMPLES: &str = "frames such as 10..20 (20 exclusive), 10.., ..20, 7, or a list of inclusive ranges such as 1-10 or 1-3,5,7-20:2";

/// `A..B`, `A..` or `..B`: a half-open range, as this program has always read it.
fn exclusive_range(spec: &str, count: u32) -> Result<FrameSet, String> {
    if spec.contains(',') {
        return Err("A..B stands alone (B exclusive); a list takes inclusive ranges A-B, e.g. 0-9,20-29 for 0..10 and 20..30".to_string());
    }
    let (a, b) = spec.split_once("..").expect("the caller saw `..`");
    let bound = |s: &str, default: u32| -> Result<u32, String> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(default);
        }
        s.parse()
            .map_err(|_| format!("{s:?} is not a frame number; expected {EXAMPLES}"))
    };
    let range = bound(a, 0)?..bound(b, count)?;
    if range.is_empty() || range.end > count {
        return Err(format!(
            "expected a non-empty range within 0..{count} (the scene has {count} frames: 0..{count} end exclusive, or 0-{} inclusive)",
            count.saturating_sub(1)
        ));
    }
    Ok(FrameSet::from(range))
}

/// One element of a list: `first`, stepping by `step` towards `end` (inclusive), as
/// written (`text`) for messages.
struct Element<'a> {
    text: &'a str,
    first: i64,
    end: i64,
    step: i64,
}

impl Element<'_> {
    /// The frames the element names, in increasing order.
    fn frames(&self) -> Vec<u32> {
        let n = (self.end - self.first) / self.step + 1;
        let mut out: Vec<u32> = (0..n)
            .map(|k| (self.first + k * self.step) as u32)
            .collect();
        if self.step < 0 {
            out.reverse();
        }
        out
    }

    /// The smallest and largest frame named (the last one reached, not the bound).
    fn extent(&self) -> (i64, i64) {
        let last = self.first + (self.end - self.first) / self.step * self.step;
        (self.first.min(last), self.first.max(last))
    }
}

/// A comma-separated list of `N`, `A-B`, `A-B:S`: checked element by element, then for
/// overlaps (as Open Job Description forbids them: a frame is listed once), then merged.
fn list(spec: &str, count: u32) -> Result<FrameSet, String> {
    let mut elements = Vec::new();
    for text in spec.split(',') {
        let e = element(text.trim())?;
        check_bounds(&e, count)?;
        elements.push(e);
    }
    elements.sort_by_key(|e| e.extent().0);
    for pair in elements.windows(2) {
        if pair[0].extent().1 >= pair[1].extent().0 {
            return Err(format!(
                "{} and {} overlap; expected each frame listed once (ranges that do not overlap)",
                pair[0].text, pair[1].text
            ));
        }
    }
    Ok(FrameSet {
        frames: elements.iter().flat_map(Element::frames).collect(),
    })
}

/// Every frame an element names lies in `0..count`.
fn check_bounds(e: &Element, count: u32) -> Result<(), String> {
    let (lo, hi) = e.extent();
    for v in [lo, hi] {
        if v < 0 || v >= i64::from(count) {
            let within = match e.text == v.to_string() {
                true => String::new(),
                false => format!(" (in {})", e.text),
            };
            return Err(format!(
                "frame {v}{within} is outside the scene's frames: expected 0-{} ({count} frames)",
                count.saturating_sub(1)
            ));
        }
    }
    Ok(())
}

/// `N`, `A-B` or `A-B:S` (spaces allowed around the numbers).
fn element(text: &str) -> Result<Element<'_>, String> {
    let what = || {
        if text.is_empty() {
            "an empty element (a comma too many); expected N, A-B or A-B:STEP".to_string()
        } else {
            format!("{text:?} is not a frame N, a range A-B or a stepped range A-B:STEP")
        }
    };
    let mut c = Cursor { rest: text };
    let first = c.int().ok_or_else(what)?;
    if c.done() {
        return Ok(Element {
            text,
            first,
            end: first,
            step: 1,
        });
    }
    if !c.eat('-') {
        return Err(what());
    }
    let end = c.int().ok_or_else(what)?;
    let step = if c.eat(':') {
        c.int().ok_or_else(what)?
    } else {
        1
    };
    if !c.done() {
        return Err(what());
    }
    check_direction(text, first, end, step)?;
    Ok(Element {
        text,
        first,
        end,
        step,
    })
}

/// A step of 0 never arrives; a step against the range's direction names nothing but its
/// first frame, which is almost certainly not what was meant.
fn check_direction(text: &str, first: i64, end: i64, step: i64) -> Result<(), String> {
    if step == 0 {
        return Err(format!("{text}: a step of 0; expected a non-zero step"));
    }
    if first > end && step > 0 {
        return Err(format!(
            "{text} runs backwards: expected A-B with A ≤ B, or a negative step to count down ({first}-{end}:-1)"
        ));
    }
    if first < end && step < 0 {
        return Err(format!(
            "{text} counts up with a negative step; expected a positive step"
        ));
    }
    Ok(())
}

/// Reads a list element left to right.
struct Cursor<'a> {
    rest: &'a str,
}

impl Cursor<'_> {
    fn skip_spaces(&mut self) {
        self.rest = self.rest.trim_start();
    }

    fn done(&mut self) -> bool {
        self.skip_spaces();
        self.rest.is_empty()
    }

    fn eat(&mut self, c: char) -> bool {
        self.skip_spaces();
        match self.rest.strip_prefix(c) {
            Some(r) => {
                self.rest = r;
                true
            }
            None => false,
        }
    }

    /// A base-10 integer with an optional `-` (a frame below 0 is then reported as out
    /// of range, not as garbage); `None` when there is none or it is past ±2³², which
    /// keeps every sum and difference of the element's numbers far from overflowing.
    fn int(&mut self) -> Option<i64> {
        let negative = self.eat('-');
        self.skip_spaces();
        let digits = self.rest.len()
            - self
                .rest
                .trim_start_matches(|c: char| c.is_ascii_digit())
                .len();
        if digits == 0 {
            return None;
        }
        let value: i64 = self.rest[..digits]
            .parse()
            .ok()
            .filter(|v| *v <= i64::from(u32::MAX))?;
        self.rest = &self.rest[digits..];
        Some(if negative { -value } else { value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(spec: &str, count: u32) -> Vec<u32> {
        FrameSet::parse(Some(spec), count)
            .unwrap_or_else(|e| panic!("{e}"))
            .iter()
            .collect()
    }

    fn error(spec: &str, count: u32) -> String {
        FrameSet::parse(Some(spec), count)
            .expect_err(spec)
            .to_string()
    }

    #[test]
    fn a_render_manager_list_names_exactly_its_frames() {
        assert_eq!(
            frames("1-3,5,7-20:2", 30),
            [1, 2, 3, 5, 7, 9, 11, 13, 15, 17, 19]
        );
        assert_eq!(frames("1-10", 11), (1..=10).collect::<Vec<_>>());
        assert_eq!(frames(" 2 - 4 , 0 ", 5), [0, 2, 3, 4]);
        // Counting down, then sorted; the step stops short of the bound.
        assert_eq!(frames("10-1:-4", 11), [2, 6, 10]);
        // Elements in any order; the set is sorted.
        assert_eq!(frames("10-15:2,1-5", 16), [1, 2, 3, 4, 5, 10, 12, 14]);
        assert_eq!(frames("7", 8), [7]);
        assert_eq!(frames("3-3", 8), [3]);
    }

    #[test]
    fn the_exclusive_range_keeps_its_meaning() {
        assert_eq!(frames("0..3", 6), [0, 1, 2]);
        assert_eq!(frames("3..6", 6), [3, 4, 5]);
        assert_eq!(frames("4..", 6), [4, 5]);
        assert_eq!(frames("..2", 6), [0, 1]);
        assert_eq!(frames("..", 3), [0, 1, 2]);
        assert_eq!(frames("5", 6), [5]);
        // 0..10 and 0-9 are the same ten frames.
        assert_eq!(frames("0..10", 10), frames("0-9", 10));
        assert_eq!(FrameSet::parse(None, 4).unwrap(), FrameSet::from(0..4));
    }

    #[test]
    fn bad_specs_name_the_value_and_what_was_expected() {
        let cases: [(&str, &[&str]); 12] = [
            ("", &["no frames", "1-3,5,7-20:2"]),
            ("  ", &["no frames"]),
            ("5-1", &["5-1 runs backwards", "5-1:-1"]),
            ("1-5:-1", &["counts up with a negative step"]),
            ("7-20:0", &["7-20:0", "step of 0", "non-zero"]),
            ("abc", &["\"abc\" is not a frame", "A-B:STEP"]),
            ("1-3,x", &["\"x\" is not a frame"]),
            ("1-3,,5", &["empty element"]),
            ("1-2-3", &["\"1-2-3\""]),
            ("1-10:4,9-15", &["1-10:4 and 9-15 overlap"]),
            ("0..3,5", &["A..B stands alone"]),
            ("x..2", &["\"x\" is not a frame number"]),
        ];
        for (spec, needles) in cases {
            let e = error(spec, 30);
            assert!(e.starts_with(&format!("--frames {spec:?}: ")), "{e}");
            for n in needles {
                assert!(e.contains(n), "{spec:?}: expected {n:?} in: {e}");
            }
        }
    }

    #[test]
    fn frames_outside_the_scene_are_refused() {
        let e = error("1-3,5,7-20:2", 10);
        assert!(
            e.contains("frame 19 (in 7-20:2)") && e.contains("expected 0-9 (10 frames)"),
            "{e}"
        );
        // The last frame reached counts, not the bound: 7-20:2 ends at 19.
        assert_eq!(frames("7-20:2", 20).last(), Some(&19));
        assert!(error("-1-3", 10).contains("frame -1 (in -1-3)"));
        assert!(error("10", 10).contains("frame 10 is outside"));
        assert!(error("5..11", 10).contains("within 0..10"));
        assert!(error("4..4", 10).contains("non-empty"));
        assert!(error("99999999999999999999", 10).contains("is not a frame"));
        // A range far past the scene is refused before anything is listed.
        assert!(error("0-4000000000", 10).contains("frame 4000000000"));
    }

    #[test]
    fn chunks_split_the_sorted_set_and_clamp_the_last() {
        let set = FrameSet::parse(Some("1-3,5,7-20:2"), 30).unwrap();
        let chunk = |i| set.chunk(4, i).map(|c| c.iter().collect::<Vec<_>>());
        assert_eq!(set.chunk_count(4), 3);
        assert_eq!(chunk(0).unwrap(), [1, 2, 3, 5]);
        assert_eq!(chunk(1).unwrap(), [7, 9, 11, 13]);
        assert_eq!(chunk(2).unwrap(), [15, 17, 19]);
        assert_eq!(chunk(3), None);
        assert_eq!(chunk(u32::MAX), None);
        assert_eq!(FrameSet::all(8).chunk(3, 2), Some(FrameSet::from(6..8)));
    }

    #[test]
    fn a_set_prints_in_the_render_managers_syntax() {
        let show = |spec: &str| FrameSet::parse(Some(spec), 40).unwrap().to_string();
        assert_eq!(show("1-3,5,7-20:2"), "1-3,5-19:2");
        assert_eq!(show("0..6"), "0-5");
        assert_eq!(show("4,7"), "4,7");
        assert_eq!(show("4,5"), "4-5");
        assert_eq!(show("30-0:-10"), "0-30:10");
        // What it prints reads back as the same set.
        for spec in ["1-3,5,7-20:2", "0,2,3,4,9,12,15,16", "39"] {
            assert_eq!(show(&show(spec)), show(spec));
            assert_eq!(
                FrameSet::parse(Some(&show(spec)), 40),
                FrameSet::parse(Some(spec), 40)
            );
        }
        let set = FrameSet::parse(Some("2-4,9"), 10).unwrap();
        assert_eq!(set.span(), 2..10);
        assert_eq!(set.as_range(), None);
        assert_eq!(FrameSet::from(3..6).as_range(), Some(3..6));
    }
}
