"""Flames: procedural flame simulation and its palettes, real flames cut out of labelled images, the
flame library a run draws sprites from, sprite files and previews, and the flame colour measured on a dataset."""
