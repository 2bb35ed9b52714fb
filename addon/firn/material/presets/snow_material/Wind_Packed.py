# Wind-packed snow: crystals broken by wind into small rounded grains, dense and hard; 350-450 kg/m^3.
# Grain radius 90 um = SSA 36 m^2/kg (wind-packed layers roughly 20-45 m^2/kg: Domine et al. 2008).
# Black carbon 10 ng/g (Doherty et al. 2010).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 9e-05
firn.impurity_black_carbon = 10.0
firn.impurity_dust = 0.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
