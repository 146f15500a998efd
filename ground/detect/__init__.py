"""Detector outputs and their evaluation: raw output to boxes (confidence, NMS, letterbox back to the image) and
COCO AP, shared by training's validation and eval's scoring so both compute the same numbers."""
