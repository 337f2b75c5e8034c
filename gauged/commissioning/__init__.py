"""Commissioning a camera (``gauged commission``): find its gauges, read their scales over several frames,
write the config that reads them and a contact sheet for the operator to confirm.

    source (photo, MCAP, Zenoh key) -> frames per camera (:mod:`.frames`)
      -> every gauge located and read on each frame, the reads of one gauge grouped by box overlap and
         its scale voted (:mod:`.survey`)
      -> config YAML (:mod:`.config_text`) and contact sheet PNG (:mod:`.sheet`)
"""
