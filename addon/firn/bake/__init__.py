"""Bake Scattering: the scene's light gathered for the core, the bake operators, its state, panels."""
