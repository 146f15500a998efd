"""Places flames are composited into or placed in: procedural and file 3D environments and their
rendering and cameras, 360° panoramas, fire-free photos and labelled frames with their estimated sites, and the
views a run draws from them."""
