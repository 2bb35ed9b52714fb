# Fresh powder: new, cold snow of intact or slightly broken crystals; typical density 50-120 kg/m^3.
# Grain radius 50 um = SSA 65 m^2/kg (fresh snow roughly 40-150 m^2/kg: Domine et al. 2008,
# Atmos. Chem. Phys. 8, 171).
# Clean remote snow: ~5 ng/g black carbon (Arctic and alpine surveys 2-30 ng/g: Doherty et al. 2010, ACP 10, 11647).
# B = 1.6 and g = 0.845 for irregular grains (Kokhanovsky & Zege 2004; Libois et al. 2014).
import bpy
firn = bpy.context.object.firn

firn.optics_mode = 'PHYSICAL'
firn.grain_radius = 5e-05
firn.impurity_black_carbon = 5.0
firn.impurity_dust = 0.0
firn.liquid_water = 0.0
firn.absorption_enhancement = 1.6
firn.anisotropy = 0.845
