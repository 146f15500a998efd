"""fuzzyfire.train: the detector, its loss, augmentations, training loop and ONNX export."""
