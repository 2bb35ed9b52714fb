"""Cycles settings light needs to cross packed ice spheres: raised where they fall short and reported, never
lowered, never changed silently."""

# Light leaving deep grain snow has crossed hundreds of ice surfaces (Chrisman): each reflection is a glossy
# bounce and each refraction a transmission bounce. 1024 is Cycles' largest setting.
GRAIN_BOUNCES = 1024
_BOUNCES = (("max_bounces", "Total"), ("glossy_bounces", "Glossy"), ("transmission_bounces", "Transmission"))
# Sky and sun reach diffuse objects under the grains only through them: refractive caustics.
_CAUSTICS = (("caustics_refractive", "Refractive Caustics"), ("caustics_reflective", "Reflective Caustics"))


def raise_light_paths(scene):
    """Raises the scene's Cycles light paths to what grain snow needs; returns what changed, as text for the
    operator's report ([] when nothing did)."""
    cycles = scene.cycles
    changes = []
    for name, label in _BOUNCES:
        old = getattr(cycles, name)
        if old < GRAIN_BOUNCES:
            setattr(cycles, name, GRAIN_BOUNCES)
            changes.append(f"{label} bounces {old} → {GRAIN_BOUNCES}")
    for name, label in _CAUSTICS:
        if not getattr(cycles, name):
            setattr(cycles, name, True)
            changes.append(f"{label} on")
    return changes
