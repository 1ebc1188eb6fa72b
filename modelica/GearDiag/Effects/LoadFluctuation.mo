within GearDiag.Effects;
model LoadFluctuation "Torque ripple from the driving or driven machine"
  extends GearDiag.GearPair(F_extra = dT/r_p*sin(2*pi*f_load*time));
  parameter Real dT(unit="N.m", min=0) = 5 "Torque ripple amplitude";
  parameter Real f_load(unit="Hz", min=0) = 7.3 "Torque ripple frequency";
  annotation(Documentation(info="<html>
<p>Torque ripple from the driving or driven machine.</p>
</html>"));
end LoadFluctuation;
