within GearDiag.Effects;
model SpeedFluctuation "The shafts' speed fluctuates: the mesh runs on a modulated angle"
  // speed = f_pinion*(1 + ds*cos(2*pi*f_speed*time)); the angle over the mean speed is
  // time + ds/(2*pi*f_speed)*sin(2*pi*f_speed*time). Every kinematic line gets phase-
  // modulation sidebands at +-f_speed (a torque ripple through the shafts' inertia, a
  // motor's slip, a drive's speed control).
  extends GearDiag.GearPair(t_angle = time + ds/(2*pi*f_speed)*sin(2*pi*f_speed*time));
  parameter Real ds(unit="1", min=0, max=1) = 0.002 "Speed fluctuation amplitude, relative to the mean speed";
  parameter Real f_speed(unit="Hz", min=0) = 7.3 "Speed fluctuation frequency";
  annotation(Documentation(info="<html>
<p>The shafts' speed fluctuates: the mesh runs on a modulated angle.</p>
<pre>
speed = f_pinion*(1 + ds*cos(2*pi*f_speed*time)); the angle over the mean speed is
time + ds/(2*pi*f_speed)*sin(2*pi*f_speed*time). Every kinematic line gets phase-
modulation sidebands at +-f_speed (a torque ripple through the shafts' inertia, a
motor's slip, a drive's speed control).
</pre>
</html>"));
end SpeedFluctuation;
