# Settled snow: days to weeks old, crystals rounded by metamorphism; typical density 200-300 kg/m^3.
# Grain radius 120 um = SSA 27 m^2/kg (decomposing and rounded grains roughly 15-60 m^2/kg:
# Domine et al. 2008).
# Black carbon 10 ng/g: typical seasonal snow away from cities (Doherty et al. 2010).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 0.00012
firn.impurity_black_carbon = 10.0
firn.impurity_dust = 0.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
