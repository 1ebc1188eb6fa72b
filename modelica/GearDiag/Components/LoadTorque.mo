within GearDiag.Components;
model LoadTorque "A constant load torque on a shaft (a brake, a generator at steady load)"
  parameter Real T(unit="N.m") = 0 "Torque the load takes from the shaft";
  GearDiag.Interfaces.Flange flange "The loaded shaft";
equation
  flange.tau = T;
  annotation(Documentation(info="<html>
<p>A constant load torque on a shaft (a brake, a generator at steady load).</p>
</html>"));
end LoadTorque;
