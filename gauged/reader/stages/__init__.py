"""The reader's stages, one module each, in pipeline order: detect, crop, keypoints, ellipse, needle, ocr,
scale, reading; with the notch check and the full-circle scale fit that serve them."""
