"""Image files and pixels: safe decoding (EXIF, bit depths, limits, a broken file named with its reason) and
what a photograph shows (its sky)."""
