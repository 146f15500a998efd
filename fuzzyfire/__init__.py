"""fuzzyfire: build and judge detectors of fuzzy objects (fire, smoke) from real and synthetic images."""

__version__ = "0.1.0"
