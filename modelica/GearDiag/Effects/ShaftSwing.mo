within GearDiag.Effects;
model ShaftSwing "Each shaft's speed swings once a turn: the mesh runs on an angle that leads and lags over each shaft's turn"
  // A drive train's torsional swing at a shaft's own speed (a misaligned coupling, a bent
  // shaft, a load or a motor that pulls harder over part of a turn): the shaft's speed is
  // f*(1 + s*cos(2*pi*f*t + psi)), its angle over its mean speed (in time, as t_angle)
  // t + s/(2*pi*f)*sin(2*pi*f*t + psi). The gear's swing turns the pinion with it through
  // the mesh; each adds to the mesh's angle. The mesh's phase is modulated at each shaft's
  // speed: sidebands of that shaft either side of every mesh harmonic, deep ones (Ng*s
  // radians at the gear's) at its second order as well, and no line at the shaft's own
  // order (the modulation of a force's phase, unlike MeshModulation's of its size or a
  // runout's transmission error). SpeedFluctuation is the same at a frequency of its own.
  extends GearDiag.GearPair(t_angle = time + s_p/(2*pi*f_pinion)*sin(2*pi*f_pinion*time + psi_p)
    + s_g/(2*pi*f_wheel)*sin(2*pi*f_wheel*time + psi_g));
  parameter Real s_p(unit="1", min=0, max=1) = 0 "Pinion shaft's speed swing once a turn, relative to its mean speed";
  parameter Real psi_p(unit="rad") = 0 "Phase of the pinion shaft's swing";
  parameter Real s_g(unit="1", min=0, max=1) = 0 "Gear shaft's speed swing once a turn, relative to its mean speed";
  parameter Real psi_g(unit="rad") = 0 "Phase of the gear shaft's swing";
  parameter Real f_wheel(unit="Hz") = f_mesh/Ng "Gear shaft speed";
  annotation(Documentation(info="<html>
<p>Each shaft's speed swings once a turn: the mesh runs on an angle that leads and lags over each shaft's turn.</p>
<pre>
A drive train's torsional swing at a shaft's own speed (a misaligned coupling, a bent
shaft, a load or a motor that pulls harder over part of a turn): the shaft's speed is
f*(1 + s*cos(2*pi*f*t + psi)), its angle over its mean speed (in time, as t_angle)
t + s/(2*pi*f)*sin(2*pi*f*t + psi). The gear's swing turns the pinion with it through
the mesh; each adds to the mesh's angle. The mesh's phase is modulated at each shaft's
speed: sidebands of that shaft either side of every mesh harmonic, deep ones (Ng*s
radians at the gear's) at its second order as well, and no line at the shaft's own
order (the modulation of a force's phase, unlike MeshModulation's of its size or a
runout's transmission error). SpeedFluctuation is the same at a frequency of its own.
</pre>
</html>"));
end ShaftSwing;
