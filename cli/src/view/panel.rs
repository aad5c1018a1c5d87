//! The viewer's side panel: the configuration and speed of each side and the keys, drawn
//! as text with the public-domain 8x8 bitmap font of `font8x8` (no font file needed).

/// Panel width in pixels: 46 glyphs of 8 pixels and a margin.
pub const WIDTH: u32 = 46 * 8 + 8;
/// Pixels from one text line to the next.
pub const LINE: u32 = 11;

const BACKGROUND: u32 = 0x0020_2024;
const TEXT: u32 = 0x00e0_e0e0;
pub const ACCENT: u32 = 0x00ff_c040;

/// A frame buffer of `0x00RRGGBB` pixels, `width` wide.
pub struct Canvas<'a> {
    pub pixels: &'a mut [u32],
    pub width: u32,
    pub height: u32,
}

impl Canvas<'_> {
    pub fn fill(&mut self, x0: u32, y0: u32, w: u32, h: u32, color: u32) {
        for y in y0..(y0 + h).min(self.height) {
            let row = (y * self.width) as usize;
            for x in x0..(x0 + w).min(self.width) {
                self.pixels[row + x as usize] = color;
            }
        }
    }

    /// Draws `text` with its top-left corner at (x, y), clipped to `max_x`.
    pub fn text(&mut self, x: u32, y: u32, max_x: u32, text: &str, color: u32) {
        for (i, c) in text.chars().enumerate() {
            let gx = x + 8 * i as u32;
            if gx + 8 > max_x.min(self.width) {
                break;
            }
            let code = if c.is_ascii() {
                c as usize
            } else {
                '?' as usize
            };
            let glyph = font8x8::legacy::BASIC_LEGACY[code];
            for (row, bits) in glyph.iter().enumerate() {
                let py = y + row as u32;
                if py >= self.height {
                    break;
                }
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        self.pixels[(py * self.width + gx + col) as usize] = color;
                    }
                }
            }
        }
    }
}

/// A line of the panel: its text and whether it stands out.
pub struct Line {
    pub text: String,
    pub accent: bool,
}

impl Line {
    pub fn plain(text: impl Into<String>) -> Line {
        Line {
            text: text.into(),
            accent: false,
        }
    }
    pub fn accent(text: impl Into<String>) -> Line {
        Line {
            text: text.into(),
            accent: true,
        }
    }
}

/// Splits `text` into lines of at most `width` glyphs, at spaces where it can.
pub fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split(' ') {
        let cur = lines.last_mut().unwrap();
        if !cur.is_empty() && cur.len() + 1 + word.len() > width {
            lines.push(String::new());
        }
        let cur = lines.last_mut().unwrap();
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(word);
        while lines.last().unwrap().len() > width {
            let cur = lines.last_mut().unwrap();
            let tail = cur.split_off(width);
            lines.push(tail);
        }
    }
    lines
}

/// Draws the panel at column `x0` (the window's right part), over its full height.
pub fn draw(canvas: &mut Canvas, x0: u32, lines: &[Line]) {
    let height = canvas.height;
    canvas.fill(x0, 0, WIDTH, height, BACKGROUND);
    let mut y = 6;
    for line in lines {
        if y + 8 > height {
            break;
        }
        let color = if line.accent { ACCENT } else { TEXT };
        canvas.text(x0 + 6, y, x0 + WIDTH, &line.text, color);
        y += LINE;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_lands_where_asked_and_is_clipped() {
        let mut px = vec![0u32; 40 * 10];
        let mut c = Canvas {
            pixels: &mut px,
            width: 40,
            height: 10,
        };
        c.text(0, 0, 40, "I", 7);
        // The glyph of `I` has ink in its first row; nothing beyond its 8 columns.
        assert!(px[..8].contains(&7));
        assert!(px.iter().enumerate().all(|(i, &p)| p == 0 || i % 40 < 8));
        let mut c = Canvas {
            pixels: &mut px,
            width: 40,
            height: 10,
        };
        // Five glyphs do not fit in 40 - 4 columns: only four are drawn.
        c.text(4, 0, 40, "IIIII", 9);
        assert!(px.iter().enumerate().all(|(i, &p)| p != 9 || i % 40 < 36));
    }

    #[test]
    fn wrap_breaks_at_spaces_and_splits_long_words() {
        assert_eq!(wrap("ab cd ef", 5), vec!["ab cd", "ef"]);
        assert_eq!(wrap("abcdefgh", 3), vec!["abc", "def", "gh"]);
    }
}
