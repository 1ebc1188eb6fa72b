within GearDiag.Effects;
model PinionEccentricity "Pinion runout: a transmission error once per pinion turn"
  extends GearDiag.GearPair(e_extra = ecc_pinion*sin(2*pi*f_pinion*time + phase_pinion));
  parameter Real ecc_pinion(unit="m", min=0) = 10e-6 "Pinion runout amplitude";
  parameter Real phase_pinion(unit="rad") = 0 "Phase of the runout";
  annotation(Documentation(info="<html>
<p>Pinion runout: a transmission error once per pinion turn (an eccentric pinion, or one
bored off its shaft's axis), the driving gear's twin of GearEccentricity.</p>
</html>"));
end PinionEccentricity;
