//! Image decoding with limits checked from the header before any pixel is decoded.

use std::io::Cursor;

use image::{
    DynamicImage, ImageDecoder, ImageFormat, ImageReader, RgbImage, metadata::Orientation,
};
use thiserror::Error;
use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;

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

/// Major brands of an ISO base media file (its `ftyp` box) that hold a HEIF image, the
/// format iPhones save photos in, which `image` does not recognise.
const HEIF_BRANDS: [&[u8]; 7] = [
    b"heic", b"heix", b"heim", b"heis", b"hevc", b"mif1", b"msf1",
];

/// The format of `bytes` from its magic number, if it is one the engine reads. A HEIF
/// photo is named as such (refused as unsupported, not as unrecognised data).
pub fn sniff(bytes: &[u8]) -> Result<ImageFormat, DecodeError> {
    if bytes.is_empty() {
        return Err(DecodeError::Empty);
    }
    if bytes.get(4..8) == Some(b"ftyp")
        && bytes.get(8..12).is_some_and(|b| HEIF_BRANDS.contains(&b))
    {
        return Err(DecodeError::Unsupported("HEIF (HEIC)".into()));
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
    header(bytes).map(|h| h.size)
}

/// What the header says.
struct Header {
    format: ImageFormat,
    /// Width and height as displayed.
    size: (u32, u32),
    /// How to turn the stored pixels upright.
    orientation: Orientation,
}

fn header(bytes: &[u8]) -> Result<Header, DecodeError> {
    let format = sniff(bytes)?;
    let read = ImageReader::with_format(Cursor::new(bytes), format)
        .into_decoder()
        .map(|mut d| (d.dimensions(), orientation(&mut d)));
    let (size, orientation) = match read {
        Ok(((w, h), o)) if turns_sideways(o) => ((h, w), o),
        Ok(((w, h), o)) => ((w, h), o),
        Err(_) if format == ImageFormat::Png && bytes.len() >= 24 && &bytes[12..16] == b"IHDR" => {
            let be =
                |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
            ((be(16), be(20)), Orientation::NoTransforms)
        }
        Err(e) => return Err(DecodeError::Corrupt(e.to_string())),
    };
    Ok(Header {
        format,
        size,
        orientation,
    })
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
/// before allocating them, and refusing corrupt or truncated JPEG data (see
/// [`decode_jpeg`]), which decoders would otherwise fill in silently.
pub fn decode_rgb(bytes: &[u8], max_pixels: u64) -> Result<RgbImage, DecodeError> {
    let Header {
        format,
        size: (width, height),
        orientation: upright,
    } = header(bytes)?;
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
    let corrupt = |e: image::ImageError| DecodeError::Corrupt(e.to_string());
    if format == ImageFormat::Jpeg {
        let mut img = DynamicImage::ImageRgb8(decode_jpeg(bytes, width.max(height))?);
        img.apply_orientation(upright);
        return Ok(img.into_rgb8());
    }
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    // The header's sides, in either order (an EXIF orientation may swap them).
    limits.max_image_width = Some(width.max(height));
    limits.max_image_height = Some(width.max(height));
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(corrupt)?;
    let mut img = DynamicImage::from_decoder(decoder).map_err(corrupt)?;
    img.apply_orientation(upright);
    Ok(img.into_rgb8())
}

/// A JPEG as stored (sensor orientation), RGB, sides at most `max_side`, decoded
/// strictly: entropy data that does not decode (bytes overwritten), or that runs out
/// before the last block (a file cut short), is an error rather than grey blocks.
///
/// The stream is decoded without its end-of-image marker: a marker would end a scan
/// that is cut short silently, while running out of data is an error in strict mode.
/// The marker is the one that ends the first image ([`jpeg_end`]): phones append data
/// after it (a Samsung trailer, a motion photo's video, a second picture), which is
/// ignored. A file that ends before it is truncated. Headers that only the lenient
/// decoder accepts (bytes between segments, which some cameras write) are decoded
/// leniently.
///
/// A progressive JPEG (many phones and image editors write them) is decoded with its
/// marker: after its last scan the decoder looks for the next marker and would run out
/// of data without one. So a progressive file cut short and given a marker back decodes
/// without its missing scans (coarser, or grey where the first scan was cut), as other
/// decoders show it; one cut with no marker is refused as any.
fn decode_jpeg(bytes: &[u8], max_side: u32) -> Result<RgbImage, DecodeError> {
    let end = jpeg_end(bytes)
        .ok_or_else(|| DecodeError::Corrupt("truncated JPEG (no end-of-image marker)".into()))?;
    let options = |strict: bool| {
        DecoderOptions::default()
            .set_strict_mode(strict)
            .jpeg_set_out_colorspace(ColorSpace::RGB)
            .set_max_width(max_side as usize)
            .set_max_height(max_side as usize)
    };
    let mut decoder = jpeg_decoder(&bytes[..end], options);
    if decoder.info().is_some_and(|i| i.sof.is_progressive()) {
        decoder = jpeg_decoder(&bytes[..end + 2], options);
    }
    let corrupt = |e: zune_jpeg::errors::DecodeErrors| DecodeError::Corrupt(format!("{e:?}"));
    let pixels = decoder.decode().map_err(corrupt)?;
    let (w, h) = decoder
        .dimensions()
        .ok_or_else(|| DecodeError::Corrupt("no frame header".into()))?;
    RgbImage::from_raw(w as u32, h as u32, pixels)
        .ok_or_else(|| DecodeError::Corrupt("decoded size differs from the header".into()))
}

/// Offset of the end-of-image marker that ends the first image of a JPEG stream, found
/// by walking its segments (skipped by their lengths, so a thumbnail inside the EXIF
/// segment does not count) and its entropy-coded data (where 0xFF is followed by a
/// stuffed zero, a restart marker or a fill byte); `None` when the data ends first.
fn jpeg_end(bytes: &[u8]) -> Option<usize> {
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    let mut i = 2;
    while i + 1 < bytes.len() {
        if bytes[i] != 0xFF {
            // Entropy-coded data, or stray bytes between segments.
            i += 1;
            continue;
        }
        i += match bytes[i + 1] {
            0xD9 => return Some(i),
            // A fill byte: the marker follows.
            0xFF => 1,
            // A stuffed zero, a restart marker, TEM or a nested SOI: no length.
            0x00 | 0x01 | 0xD0..=0xD8 => 2,
            _ => 2 + u16::from_be_bytes([*bytes.get(i + 2)?, *bytes.get(i + 3)?]) as usize,
        };
    }
    None
}

/// A JPEG decoder over `stream` with its headers read: strictly, or leniently where only
/// the lenient decoder reads them.
fn jpeg_decoder(
    stream: &[u8],
    options: impl Fn(bool) -> DecoderOptions,
) -> zune_jpeg::JpegDecoder<ZCursor<&[u8]>> {
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(stream), options(true));
    if decoder.decode_headers().is_err() {
        decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(stream), options(false));
    }
    decoder
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
    fn corrupt_jpeg_data_is_refused() {
        let photo = RgbImage::from_fn(160, 120, |x, y| {
            image::Rgb([
                (x * 3 % 256) as u8,
                (y * 5 % 256) as u8,
                ((x ^ y) % 256) as u8,
            ])
        });
        let mut jpeg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
            .encode_image(&photo)
            .unwrap();
        assert_eq!(
            decode_rgb(&jpeg, u64::MAX).unwrap().dimensions(),
            (160, 120)
        );
        // A greyscale JPEG comes out RGB.
        let grey = image::GrayImage::from_fn(40, 30, |x, _| image::Luma([(x * 6) as u8]));
        let mut grey_jpeg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut grey_jpeg, 90)
            .encode_image(&grey)
            .unwrap();
        let decoded = decode_rgb(&grey_jpeg, u64::MAX).unwrap();
        let px = decoded.get_pixel(20, 10).0;
        assert!(
            px[0] == px[1] && px[1] == px[2] && px[0].abs_diff(120) <= 3,
            "{px:?}"
        );
        // Cut in half with an end-of-image marker appended.
        let mut cut = jpeg[..jpeg.len() / 2].to_vec();
        cut.extend([0xFF, 0xD9]);
        assert!(matches!(
            decode_rgb(&cut, u64::MAX),
            Err(DecodeError::Corrupt(_))
        ));
        // Cut with no marker.
        assert!(matches!(
            decode_rgb(&jpeg[..jpeg.len() - 100], u64::MAX),
            Err(DecodeError::Corrupt(_))
        ));
    }

    /// `tests/data/progressive.jpg` and `restart.jpg`: a 160x120 gradient (red =
    /// x·255/159, green = y·255/119, blue 128) saved as JPEG, quality 90, by Pillow:
    /// progressive (`progressive=True, optimize=True`: SOF2 and ten scans), and
    /// baseline with a restart marker after every MCU (`restart_marker_blocks=1`).
    const PROGRESSIVE: &[u8] = include_bytes!("../tests/data/progressive.jpg");
    const RESTART: &[u8] = include_bytes!("../tests/data/restart.jpg");

    /// Mean absolute error, per channel, of a decoded gradient fixture.
    fn gradient_error(jpeg: &[u8]) -> f64 {
        let img = decode_rgb(jpeg, u64::MAX).unwrap();
        assert_eq!(img.dimensions(), (160, 120));
        img.enumerate_pixels()
            .map(|(x, y, p)| {
                let want = [x * 255 / 159, y * 255 / 119, 128];
                (0..3)
                    .map(|c| (p.0[c] as f64 - want[c] as f64).abs())
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (160.0 * 120.0 * 3.0)
    }

    #[test]
    fn restart_markers_do_not_end_the_image() {
        let err = gradient_error(RESTART);
        assert!(err < 2.0, "mean error {err}");
    }

    #[test]
    fn progressive_jpeg_is_decoded_and_a_cut_one_refused() {
        let err = gradient_error(PROGRESSIVE);
        assert!(err < 2.0, "mean error {err}");
        // Cut within its scans, no marker.
        assert!(matches!(
            decode_rgb(&PROGRESSIVE[..PROGRESSIVE.len() - 300], u64::MAX),
            Err(DecodeError::Corrupt(_))
        ));
    }

    #[test]
    fn data_after_the_image_is_ignored_and_a_thumbnail_does_not_end_it() {
        let photo = RgbImage::from_fn(64, 48, |x, y| {
            image::Rgb([(x * 4) as u8, (y * 5) as u8, 90])
        });
        let mut jpeg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
            .encode_image(&photo)
            .unwrap();
        let plain = decode_rgb(&jpeg, u64::MAX).unwrap();
        // A phone's trailer after the end marker: zeros, then bytes with markers in them.
        let mut trailed = jpeg.clone();
        trailed.extend(b"SEFH");
        trailed.extend(std::iter::repeat_n(0u8, 2000));
        trailed.extend((0..5000u32).map(|k| (k * 97 % 251) as u8));
        trailed.extend([0xFF, 0xD9, 0x12, 0x34]);
        assert_eq!(decode_rgb(&trailed, u64::MAX).unwrap(), plain);
        // An APP1 segment right after SOI holding a thumbnail's end marker.
        let payload = [b"Exif\0\0".as_slice(), &[0xFF, 0xD8, 0x00, 0xFF, 0xD9]].concat();
        let mut app1 = vec![0xFF, 0xE1];
        app1.extend(((payload.len() + 2) as u16).to_be_bytes());
        app1.extend(&payload);
        let with_thumb = [&jpeg[..2], &app1[..], &jpeg[2..]].concat();
        assert_eq!(jpeg_end(&with_thumb), Some(with_thumb.len() - 2));
        assert_eq!(decode_rgb(&with_thumb, u64::MAX).unwrap(), plain);
        // Cut short, with a trailer-like tail that holds no end marker.
        let mut cut = jpeg[..jpeg.len() / 2].to_vec();
        cut.extend(std::iter::repeat_n(0u8, 100));
        assert!(matches!(
            decode_rgb(&cut, u64::MAX),
            Err(DecodeError::Corrupt(_))
        ));
    }

    #[test]
    fn a_heif_photo_is_named_as_unsupported() {
        let mut heic = 24u32.to_be_bytes().to_vec();
        heic.extend(b"ftypheic\0\0\0\0mif1heic");
        heic.extend([0; 64]);
        assert_eq!(
            sniff(&heic),
            Err(DecodeError::Unsupported("HEIF (HEIC)".into()))
        );
        assert_eq!(sniff(&heic[..10]), Err(DecodeError::Unrecognised));
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
