within GearDiag.Components;
model SteadySpeed "A drive that holds its shaft at the steady speed (a stiff speed-controlled motor)"
  // The flange turns at its steady speed exactly: its deviation is 0, whatever torque the
  // drive train asks. A drive with a speed ripple gives the deviation as a modifier.
  GearDiag.Interfaces.Flange flange "The driven shaft";
  Real w(unit="rad/s") = 0 "Speed over the steady speed";
equation
  flange.w = w;
  annotation(Documentation(info="<html>
<p>A drive that holds its shaft at the steady speed (a stiff speed-controlled motor).</p>
<pre>
The flange turns at its steady speed exactly: its deviation is 0, whatever torque the
drive train asks. A drive with a speed ripple gives the deviation as a modifier.
</pre>
</html>"));
end SteadySpeed;
