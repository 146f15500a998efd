"""fuzzyfire.eval: ONNX scoring, COCO metrics, seed statistics and reports."""
