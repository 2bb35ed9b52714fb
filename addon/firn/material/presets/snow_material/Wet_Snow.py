# Wet snow: melting, rounded grains and clusters with liquid water in the pores; 400-550 kg/m^3.
# Grain radius 500 um = SSA 6.5 m^2/kg (melt forms roughly 2-10 m^2/kg: Domine et al. 2008).
# Liquid water 5 % by volume: the ICSSG class 'wet' is 3-8 % (Fierz et al. 2009, The International
# Classification for Seasonal Snow on the Ground). Black carbon 20 ng/g: melt concentrates it at the surface
# (Doherty et al. 2010).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 0.0005
firn.impurity_black_carbon = 20.0
firn.impurity_dust = 0.0
firn.liquid_water = 0.05
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
