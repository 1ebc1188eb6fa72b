within GearDiag.Effects;
model MeshModulation "The mesh stiffness modulated once per turn of each shaft"
  // A gear mounted tilted or eccentric carries its load on a face width that varies
  // around its turn: the mesh stiffness (its mean and the wave a*sigma, the faulty pinion
  // tooth's as it is) is scaled by 1 + m_p*cos(pinion angle + phi_p) + m_g*cos(gear angle
  // + phi_g). Amplitude-modulation sidebands at one order of each shaft either side of
  // every mesh harmonic, and the deflection under load at that order (a runout's
  // transmission error, GearEccentricity and the pair's f_ate, modulates the mesh's phase
  // instead).
  extends GearDiag.GearPair(k_mod = (1 + a*sigma)*(m_p*cos(2*pi*f_pinion*t_angle + phi_p)
    + m_g*cos(2*pi*f_wheel*t_angle + phi_g)));
  parameter Real m_p(unit="1", min=0, max=1) = 0 "Depth of the stiffness's modulation once per pinion turn";
  parameter Real phi_p(unit="rad") = 0 "Phase of the pinion turn's modulation";
  parameter Real m_g(unit="1", min=0, max=1) = 0 "Depth of the stiffness's modulation once per gear turn";
  parameter Real phi_g(unit="rad") = 0 "Phase of the gear turn's modulation";
  parameter Real f_wheel(unit="Hz") = f_mesh/Ng "Gear shaft speed";
  annotation(Documentation(info="<html>
<p>The mesh stiffness modulated once per turn of each shaft.</p>
<pre>
A gear mounted tilted or eccentric carries its load on a face width that varies
around its turn: the mesh stiffness (its mean and the wave a*sigma, the faulty pinion
tooth's as it is) is scaled by 1 + m_p*cos(pinion angle + phi_p) + m_g*cos(gear angle
+ phi_g). Amplitude-modulation sidebands at one order of each shaft either side of
every mesh harmonic, and the deflection under load at that order (a runout's
transmission error, GearEccentricity and the pair's f_ate, modulates the mesh's phase
instead).
</pre>
</html>"));
end MeshModulation;
