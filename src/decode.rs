//! Image decoding with limits checked from the header before any pixel is decoded.

use std::io::Cursor;

use image::{
    DynamicImage, ImageDecoder, ImageFormat, ImageReader, RgbImage, metadata::Orientation,
};
use thiserror::Error;

/// Why bytes could not become an RGB image.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DecodeError {
    /// No bytes at all.
    #[error("the image is empty (0 bytes)")]
    Empty,
    /// A known image format other than JPEG or PNG.
    #[error("unsupported image format: expected JPEG or PNG, got {0}")]
    Unsupported(String),
    /// Not recognisable as any image format.
    #[error("the data is not a JPEG or PNG image (unrecognised signature)")]
    Unrecognised,
    /// The header announces more pixels than allowed.
    #[error("image is {width}x{height} = {pixels} pixels, over the limit of {limit}")]
    TooManyPixels {
        /// Width from the header.
        width: u32,
        /// Height from the header.
        height: u32,
        /// width × height.
        pixels: u64,
        /// The configured limit.
        limit: u64,
    },
    /// The data is corrupt or truncated.
    #[error("the image could not be decoded: {0}")]
    Corrupt(String),
}

/// The format of `bytes` from its magic number, if it is one the engine reads.
pub fn sniff(bytes: &[u8]) -> Result<ImageFormat, DecodeError> {
    if bytes.is_empty() {
        return Err(DecodeError::Empty);
    }
    match image::guess_format(bytes) {
        Ok(f @ (ImageFormat::Jpeg | ImageFormat::Png)) => Ok(f),
        Ok(other) => Err(DecodeError::Unsupported(format!("{other:?}"))),
        Err(_) => Err(DecodeError::Unrecognised),
    }
}

/// Width and height of the photo as displayed (its EXIF orientation applied), from the
/// header alone: no pixel is decoded. A PNG whose header the decoder refuses (a file
/// that is only a header, a "pixel bomb") is measured from its IHDR chunk, so it is
/// refused for its size rather than as truncated.
pub fn dimensions(bytes: &[u8]) -> Result<(u32, u32), DecodeError> {
    let format = sniff(bytes)?;
    let header = ImageReader::with_format(Cursor::new(bytes), format)
        .into_decoder()
        .map(|mut d| (d.dimensions(), orientation(&mut d)));
    match header {
        Ok(((w, h), o)) if turns_sideways(o) => Ok((h, w)),
        Ok(((w, h), _)) => Ok((w, h)),
        Err(_) if format == ImageFormat::Png && bytes.len() >= 24 && &bytes[12..16] == b"IHDR" => {
            let be =
                |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
            Ok((be(16), be(20)))
        }
        Err(e) => Err(DecodeError::Corrupt(e.to_string())),
    }
}

/// The photo's EXIF orientation; none (or an unreadable one) means upright.
fn orientation(decoder: &mut impl ImageDecoder) -> Orientation {
    decoder.orientation().unwrap_or(Orientation::NoTransforms)
}

/// True for the orientations that swap width and height.
fn turns_sideways(o: Orientation) -> bool {
    matches!(
        o,
        Orientation::Rotate90
            | Orientation::Rotate270
            | Orientation::Rotate90FlipH
            | Orientation::Rotate270FlipH
    )
}

/// Decodes JPEG or PNG `bytes` to 8-bit RGB as displayed (EXIF orientation applied, so
/// that coordinates are those a person sees), refusing more than `max_pixels` pixels
/// before allocating them, and refusing truncated JPEG streams (no end-of-image
/// marker), which decoders would otherwise fill in silently.
pub fn decode_rgb(bytes: &[u8], max_pixels: u64) -> Result<RgbImage, DecodeError> {
    let format = sniff(bytes)?;
    let (width, height) = dimensions(bytes)?;
    if width == 0 || height == 0 {
        return Err(DecodeError::Corrupt(format!(
            "the header announces {width}x{height} pixels"
        )));
    }
    let pixels = width as u64 * height as u64;
    if pixels > max_pixels {
        return Err(DecodeError::TooManyPixels {
            width,
            height,
            pixels,
            limit: max_pixels,
        });
    }
    if format == ImageFormat::Jpeg && !has_jpeg_end(bytes) {
        return Err(DecodeError::Corrupt(
            "truncated JPEG (no end-of-image marker)".into(),
        ));
    }
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    // The header's sides, in either order (an EXIF orientation may swap them).
    limits.max_image_width = Some(width.max(height));
    limits.max_image_height = Some(width.max(height));
    reader.limits(limits);
    let corrupt = |e: image::ImageError| DecodeError::Corrupt(e.to_string());
    let mut decoder = reader.into_decoder().map_err(corrupt)?;
    let upright = orientation(&mut decoder);
    let mut img = DynamicImage::from_decoder(decoder).map_err(corrupt)?;
    img.apply_orientation(upright);
    Ok(img.into_rgb8())
}

/// True when the JPEG stream ends with EOI (0xFFD9), allowing trailing padding.
fn has_jpeg_end(bytes: &[u8]) -> bool {
    let tail = &bytes[bytes.len().saturating_sub(64)..];
    tail.windows(2).any(|w| w == [0xFF, 0xD9])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png_bytes(w: u32, h: u32) -> Vec<u8> {
        crate::pipeline::rgb_png(&RgbImage::from_pixel(w, h, image::Rgb([7, 7, 7]))).unwrap()
    }

    #[test]
    fn decodes_png_and_rejects_bad_input() {
        let img = decode_rgb(&png_bytes(20, 10), 1000).unwrap();
        assert_eq!(img.dimensions(), (20, 10));
        assert_eq!(decode_rgb(&[], 10), Err(DecodeError::Empty));
        assert_eq!(
            decode_rgb(b"hello world", 10),
            Err(DecodeError::Unrecognised)
        );
        assert!(matches!(
            decode_rgb(b"GIF89a......", 10),
            Err(DecodeError::Unsupported(_))
        ));
        assert!(matches!(
            decode_rgb(&png_bytes(20, 10), 100),
            Err(DecodeError::TooManyPixels { pixels: 200, .. })
        ));
        let bytes = png_bytes(20, 10);
        assert!(matches!(
            decode_rgb(&bytes[..bytes.len() / 2], 1000),
            Err(DecodeError::Corrupt(_))
        ));
    }

    #[test]
    fn huge_header_is_refused_without_decoding() {
        // A PNG header announcing 60000x60000 with no pixel data behind it.
        let bytes = crate::synth::png_header_only(60000, 60000);
        assert_eq!(dimensions(&bytes).unwrap(), (60000, 60000));
        assert!(matches!(
            decode_rgb(&bytes, 1 << 24),
            Err(DecodeError::TooManyPixels { .. })
        ));
    }
}
