"""The ground floor every package stands on: the dataset model (COCO-canonical), format readers and writers,
safe image IO, folder walking, box math, NMS, manifests, problems, class names, letterboxing, COCO evaluation,
detector outputs, devices, progress bars, the typed YAML config loader and the helpers every package's commands
share. Nothing here imports from the rest of :mod:`curate` (curation, the mixer, the commands), so synth, train
and eval build on it without pulling in curation."""
