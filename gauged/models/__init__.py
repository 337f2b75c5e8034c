"""The trained ONNX models shipped with gauged (see README.md here)."""
