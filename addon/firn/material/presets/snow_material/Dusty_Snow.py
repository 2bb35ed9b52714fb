# Dusty snow: spring snow after desert dust events, tinted orange-brown; 300-450 kg/m^3.
# Grain radius 400 um = SSA 8.2 m^2/kg (aged spring snow: Domine et al. 2008).
# Dust 1000 ug/g and black carbon 30 ng/g: Colorado Rockies surfaces reach 0.1-5 mg/g of dust at the end of
# the season (Painter et al. 2012, Water Resour. Res. 48, W07521; Skiles & Painter 2017, J. Glaciol. 63, 118).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 0.0004
firn.impurity_black_carbon = 30.0
firn.impurity_dust = 1000.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
