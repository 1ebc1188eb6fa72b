within GearDiag.Functions;
function meshStiffness "Mesh stiffness of a pair relative to its mean: the paper's wave, its faulty pinion tooth and the stiffness shape beyond it"
  // k/K = 1 + a(tooth)*sigma(2*pi*u, f_f) + k2*cos(4*pi*u + phi2) + k4*cos(8*pi*u + phi4)
  //         - d_f*toothWindow(u, Np, 0, eps_c, q_c, r_c)
  // a is a_f while pinion tooth 0 is in mesh, a0 otherwise. Tooth periods start a quarter
  // mesh cycle early, where sigma = 0, so the jump of a between teeth leaves k continuous
  // and the solver sees no discontinuity. GearPair's and GearMesh's law.
  input Real u "Mesh cycles since the start (f_mesh*t_angle)";
  input Integer Np "Number of pinion teeth";
  input Real a0 "Stiffness variation amplitude of the healthy teeth, relative to K";
  input Real a_f "Stiffness variation amplitude of the faulty pinion tooth, relative to K";
  input Real f_f "Form factor of the stiffness wave: 0 cosine, towards 1 square";
  input Real k2 "Second mesh harmonic of the stiffness, relative to K";
  input Real phi2(unit="rad") "Phase of the second mesh harmonic";
  input Real k4 "Fourth mesh harmonic of the stiffness, relative to K";
  input Real phi4(unit="rad") "Phase of the fourth mesh harmonic";
  input Real d_f "Relative loss of mesh stiffness while the faulty pinion tooth is alone in contact";
  input Real eps_c "Contact ratio: mesh cycles a tooth is in contact for";
  input Real q_c "Loss while the faulty tooth is alone in contact over its loss in double contact";
  input Real r_c "Mesh cycles over which the load passes between tooth pairs";
  output Real k "Mesh stiffness over its mean K";
protected
  Real a "Stiffness variation amplitude of the tooth in mesh";
algorithm
  a := if mod(floor(u + 0.25), Np) < 0.5 then a_f else a0;
  k := 1 + a*GearDiag.Functions.formWave(2*GearDiag.pi*u, f_f)
    + k2*cos(4*GearDiag.pi*u + phi2) + k4*cos(8*GearDiag.pi*u + phi4)
    - d_f*GearDiag.Functions.toothWindow(u, Np, 0, eps_c, q_c, r_c);
end meshStiffness;
