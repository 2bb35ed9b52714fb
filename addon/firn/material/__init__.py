"""Snow Material: optics from physical parameters, the snow's shader nodes, presets, panels."""
