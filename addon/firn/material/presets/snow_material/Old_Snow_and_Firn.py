# Old snow and firn: coarse melt-freeze polycrystals surviving a season or more; 500-830 kg/m^3.
# Grain radius 800 um = SSA 4.1 m^2/kg (melt forms and firn roughly 2-10 m^2/kg: Domine et al. 2008).
# Black carbon 20 ng/g and dust 10 ug/g: impurities accumulate as old surfaces melt and sublimate
# (Doherty et al. 2010).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 0.0008
firn.impurity_black_carbon = 20.0
firn.impurity_dust = 10.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
