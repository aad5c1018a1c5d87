//! plotters' bitmap backend with text drawn from the public-domain 8x8 bitmap font of
//! `font8x8`, so the PNG plots need no font file.

use plotters::backend::BitMapBackend;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle as Style, BackendTextStyle, DrawingErrorKind,
};

/// plotters' bitmap backend with text: without its `ttf` feature (fontconfig, system
/// fonts) plotters cannot rasterize text, so this draws it with the public-domain 8x8
/// bitmap font of `font8x8`, scaled by whole pixels, and delegates everything else.
pub struct TextBitmap<'a>(pub BitMapBackend<'a>);

type BackendResult<T, E> = Result<T, DrawingErrorKind<E>>;

impl TextBitmap<'_> {
    /// Pixel scale of the 8x8 glyphs for a font size; glyphs advance by 8 x scale.
    fn scale(size: f64) -> i32 {
        ((size * 0.455 / 8.0).floor() as i32).max(1)
    }
}

impl<'a> DrawingBackend for TextBitmap<'a> {
    type ErrorType = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> BackendResult<(), Self::ErrorType> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> BackendResult<(), Self::ErrorType> {
        self.0.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: Style>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: Style>(
        &mut self,
        ul: BackendCoord,
        br: BackendCoord,
        style: &S,
        fill: bool,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_rect(ul, br, style, fill)
    }
    fn draw_path<S: Style, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_path(path, style)
    }
    fn draw_circle<S: Style>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: Style, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.fill_polygon(vert, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> BackendResult<(u32, u32), Self::ErrorType> {
        let s = Self::scale(style.size()) as u32;
        Ok((8 * s * text.chars().count() as u32, 8 * s))
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> BackendResult<(), Self::ErrorType> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let s = Self::scale(style.size());
        let (w, h) = (8 * s * text.chars().count() as i32, 8 * s);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let transform = style.transform();
        let (bw, bh) = self.get_size();
        for (i, ch) in text.chars().enumerate() {
            let code = if ch.is_ascii() {
                ch as usize
            } else {
                '?' as usize
            };
            let glyph = font8x8::legacy::BASIC_LEGACY[code];
            for (gy, row) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if (row >> gx) & 1 == 0 {
                        continue;
                    }
                    for sy in 0..s {
                        for sx in 0..s {
                            let x = i as i32 * 8 * s + gx * s + sx + dx;
                            let y = gy as i32 * s + sy + dy;
                            let (x, y) = transform.transform(x, y);
                            let (x, y) = (pos.0 + x, pos.1 + y);
                            if x >= 0 && y >= 0 && x < bw as i32 && y < bh as i32 {
                                self.0.draw_pixel((x, y), color)?;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
