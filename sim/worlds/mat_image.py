"""A printed mat from a file: PNG, JPEG or PDF into the RGB raster the mat texture and sensors read.

The raster is stretched onto the mat's printed size by the texture mapping itself (texrepeat 1 1
over the mat plane), so any pixel count maps exactly onto size_mm; nothing here resamples to a
size. What it does bound is resolution: a sensor's footprint is millimetres wide, so texels finer
than MAX_PX_PER_MM (the built-in mats' own resolution) add memory and load time without changing a
reading: a larger image is box-filtered down once as it is decoded (Pillow's reduce, then a
resize), which keeps an edge where it was printed to a fraction of a texel. A PDF's first page is
rendered at that resolution directly. Nothing is kept after the build: the compiled model holds
the one copy the sensors read, and a process of a 4000 x 2000 px mat stays within its memory bar.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

MAX_PX_PER_MM = 1.0  # 1 mm texels, as the built-in mats: a line edge lands within a fraction of a mm


class MatImageError(ValueError):
    """A mat image that cannot be read: one line naming the file."""


def load_mat(path, size_mm: tuple[float, float]) -> np.ndarray:
    """(H, W, 3) uint8 of the mat, row 0 its far (+y) edge, at most MAX_PX_PER_MM texels per mm."""
    path = Path(path)
    try:
        stat = path.stat()
    except OSError:
        raise MatImageError(f"{path}: mat image does not exist") from None
    return _load(str(path.resolve()), stat.st_mtime_ns, stat.st_size, float(size_mm[0]), float(size_mm[1]))


def _load(path: str, _mtime_ns: int, _size: int, width_mm: float, height_mm: float) -> np.ndarray:
    limit = (max(1, round(width_mm * MAX_PX_PER_MM)), max(1, round(height_mm * MAX_PX_PER_MM)))
    if path.lower().endswith(".pdf"):
        pixels = _render_pdf(path, width_mm, limit)
    else:
        pixels = _decode(path, limit)
    return pixels


def _decode(path: str, limit: tuple[int, int]) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            if image.format == "JPEG":
                image.draft("RGB", limit)  # let the decoder skip detail it would throw away
            if image.width > limit[0] or image.height > limit[1]:
                factor = max(1, min(image.width // limit[0], image.height // limit[1]))
                if factor > 1:
                    image = image.reduce(factor)
                if image.width > limit[0] or image.height > limit[1]:
                    scale = min(limit[0] / image.width, limit[1] / image.height)
                    image = image.resize(
                        (max(1, round(image.width * scale)), max(1, round(image.height * scale))),
                        Image.Resampling.BOX,
                    )
            if image.mode != "RGB":
                image = _flatten(image)
            return np.asarray(image, dtype=np.uint8)
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise MatImageError(f"{path}: not a readable PNG or JPEG image ({exc})") from None


def _flatten(image):
    """RGB of any mode; a transparent pixel is white paper, as a printed mat has."""
    from PIL import Image

    if image.mode in ("RGBA", "LA", "PA") or (image.mode == "P" and "transparency" in image.info):
        rgba = image.convert("RGBA")
        paper = Image.new("RGB", rgba.size, (255, 255, 255))
        paper.paste(rgba, mask=rgba.getchannel("A"))
        return paper
    return image.convert("RGB")


def _render_pdf(path: str, width_mm: float, limit: tuple[int, int]) -> np.ndarray:
    try:
        import pypdfium2 as pdfium
    except ImportError:
        raise MatImageError(
            f"{path}: reading a PDF mat needs pypdfium2, which comes with the [sim] extra"
        ) from None
    try:
        document = pdfium.PdfDocument(path)
    except pdfium.PdfiumError as exc:
        raise MatImageError(f"{path}: not a readable PDF ({exc})") from None
    try:
        if len(document) < 1:
            raise MatImageError(f"{path}: the PDF has no pages")
        page = document[0]
        width_pt, height_pt = page.get_size()
        scale = min(limit[0] / width_pt, limit[1] / height_pt)
        bitmap = page.render(scale=scale, fill_color=(255, 255, 255, 255))
        image = bitmap.to_pil().convert("RGB")
        return np.asarray(image, dtype=np.uint8)
    finally:
        document.close()
