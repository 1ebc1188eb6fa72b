within GearDiag.Interfaces;
connector Flange "A shaft's end: its speed over its steady speed, and the torque through it"
  // A gearbox's vibration is small beside its turning, so a shaft's state is its
  // deviation from the steady rotation, not its angle (thousands of radians after a few
  // seconds, against micro-radians of vibration: a solver's tolerance on the angle would
  // swamp the vibration). The deviation's speed is the potential; a component that
  // deforms (a shaft, a mesh) keeps its own deformation as a state, so connected models
  // need no index reduction.
  Real w(unit="rad/s") "Speed of the shaft end over its steady speed, in its own sense of turning";
  flow Real tau(unit="N.m") "Torque the shaft end passes into the component";
  annotation(Documentation(info="<html>
<p>A shaft's end: its speed over its steady speed, and the torque through it.</p>
<pre>
A gearbox's vibration is small beside its turning, so a shaft's state is its
deviation from the steady rotation, not its angle (thousands of radians after a few
seconds, against micro-radians of vibration: a solver's tolerance on the angle would
swamp the vibration). The deviation's speed is the potential; a component that
deforms (a shaft, a mesh) keeps its own deformation as a state, so connected models
need no index reduction.
</pre>
</html>"));
end Flange;
