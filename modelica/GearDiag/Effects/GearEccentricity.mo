within GearDiag.Effects;
model GearEccentricity "Driven-gear runout: a transmission error once per gear turn"
  extends GearDiag.GearPair(e_extra = ecc_gear*sin(2*pi*f_gear*time + phase_gear));
  parameter Real ecc_gear(unit="m", min=0) = 10e-6 "Gear runout amplitude";
  parameter Real phase_gear(unit="rad") = 0 "Phase of the runout";
  parameter Real f_gear(unit="Hz") = f_mesh/Ng "Gear shaft speed";
  annotation(Documentation(info="<html>
<p>Driven-gear runout: a transmission error once per gear turn.</p>
</html>"));
end GearEccentricity;
