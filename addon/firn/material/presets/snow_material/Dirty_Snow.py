# Dirty snow: urban or roadside snow darkened by soot and grit; 300-500 kg/m^3.
# Grain radius 300 um = SSA 11 m^2/kg (aged rounded grains: Domine et al. 2008).
# Black carbon 1000 ng/g and dust 200 ug/g: snow near cities and roads holds hundreds to thousands of ng/g of
# black carbon (industrial north-east China up to several thousand: Wang, Doherty & Huang 2013, JGR 118, 1471).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 0.0003
firn.impurity_black_carbon = 1000.0
firn.impurity_dust = 200.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
