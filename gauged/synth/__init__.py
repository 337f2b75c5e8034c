"""Synthetic gauges with complete ground truth: stills, crops, moving recordings (docs/synth.md).

Public entry points (all deterministic from a seed or a ``numpy.random.Generator``):

- :func:`gauged.synth.crop.render_crop` - a square crop of one gauge (any size, e.g. 448 px) with
  its truth in crop pixels and a needle label map (0 background, 1 pointing part, 2 counterweight);
- :func:`gauged.synth.scene.render_scene` - a full frame with several gauges and its truth;
- :func:`gauged.synth.recording.write_foxglove` / :func:`~gauged.synth.recording.write_ros2` -
  moving scenes (:mod:`gauged.synth.sequence`) as MCAP with a truth channel per camera.

The truth schema is documented in :mod:`gauged.synth.truth`. The pipeline: parameters are drawn
(:mod:`~gauged.synth.sampling`), the dial is drawn frontally (:mod:`~gauged.synth.dial`,
:mod:`~gauged.synth.needle`, :mod:`~gauged.synth.glass`), warped through the homography of a
camera pose (:mod:`~gauged.synth.projection`) into a frame with a background, case, shadow and
occluders (:mod:`~gauged.synth.scene`), and passed through a camera model
(:mod:`~gauged.synth.camera`); every labelled point goes through the same homography.

:mod:`gauged.synth.moving_dials` is the older, simpler recording generator of ``recordings/demo.mcap``.
"""
