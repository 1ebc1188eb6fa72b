within GearDiag.Interfaces;
partial model PartialMeshLaw "The law of a gear mesh: its parameters, stiffness and transmission errors, on the pinion's angle"
  // k(t) = K*(1 + a(tooth)*sigma(theta_mesh, f_f) + k2*cos(2*theta_mesh + phi2)
  //            + k4*cos(4*theta_mesh + phi4) - d_f*w0(theta_mesh) + k_mod)   Eq. (3) and beyond
  // e_ate = f_ate*xi_max*sin(w_pinion*t)                         assembly TE, Eq. (4)
  // e_dte = f_dte*gamma_max*sin(w_fe*t)                          geometric TE, Eq. (5), w_fe = w_mesh/N_ap
  // The kinematics run on t_angle, the pinion angle over its mean speed (= time).
  // GearPair (the paper's SDOF pair) and Components.GearMesh (a stage between two shafts)
  // extend it; k_mod, e_extra and t_angle are hooks with neutral declaration equations.
  // ---- fault parameters (normalised, estimated by pydiag) ----
  parameter Real a0(unit="1", min=0, max=0.9) = 0.1 "Stiffness variation amplitude of the healthy teeth, relative to K";
  parameter Real a_f(unit="1", min=0, max=0.9) = 0.1 "Stiffness variation amplitude of the faulty pinion tooth, relative to K";
  parameter Real f_f(unit="1", min=0, max=0.99) = 0.1 "Form factor of the stiffness wave: 0 cosine, towards 1 square";
  parameter Real f_ate(unit="1", min=0, max=1) = 0 "Assembly transmission error level, 0..1 of xi_max";
  parameter Real f_dte(unit="1", min=0, max=1) = 0 "Geometric transmission error level, 0..1 of gamma_max";

  // ---- shape of the mesh stiffness wave beyond the paper's ----
  // A contact ratio other than 1.5 (or tip relief) gives the healthy mesh's stiffness even
  // harmonics that no form factor can: 0 is the paper's wave.
  parameter Real k2(unit="1", min=0, max=1) = 0 "Second mesh harmonic of the stiffness, relative to K";
  parameter Real phi2(unit="rad") = 0 "Phase of the second mesh harmonic of the stiffness";
  parameter Real k4(unit="1", min=0, max=1) = 0 "Fourth mesh harmonic of the stiffness, relative to K";
  parameter Real phi4(unit="rad") = 0 "Phase of the fourth mesh harmonic of the stiffness";
  // A cracked or chipped tooth is also softer over its whole contact, which the paper's
  // amplitude a_f cannot say: the mesh stiffness drops by d_f of K while the faulty tooth
  // carries the load alone, and by d_f/q_c while it shares it with a neighbour pair (q_c
  // is 2 for two equal pairs on rigid shafts; shafts and bearings in series make it
  // larger); w0 is that two-level loss over eps_c mesh cycles, its steps eased over r_c
  // cycles (GearDiag.Functions.toothWindow). 0 is the paper's tooth.
  parameter Real d_f(unit="1", min=0, max=1) = 0 "Relative loss of mesh stiffness while the faulty pinion tooth is alone in contact";
  parameter Real eps_c(unit="1", min=1, max=2) = 1.5 "Contact ratio: mesh cycles a tooth is in contact for";
  parameter Real q_c(unit="1", min=1) = 2 "Loss while the faulty tooth is alone in contact over its loss in double contact";
  parameter Real r_c(unit="1", min=1e-3, max=1) = 0.1 "Mesh cycles over which the load passes between tooth pairs";

  // ---- kinematics ----
  parameter Integer Np = 14 "Number of pinion teeth";
  parameter Integer Ng = 21 "Number of gear teeth";
  parameter Real f_pinion(unit="Hz") = 25 "Pinion shaft speed (1500 rpm)";

  // ---- physical parameters ----
  parameter Real K(unit="N/m") = 2e8 "Mean mesh stiffness";
  parameter Real c(unit="N.s/m") = 1000 "Mesh damping (damping ratio 0.05 with the defaults)";
  parameter Real T(unit="N.m") = 50 "Pinion torque";
  parameter Real r_p(unit="m") = 0.03 "Pinion pitch radius";
  parameter Real xi_max(unit="m") = 50e-6 "Assembly TE amplitude at f_ate = 1 (pinion runout)";
  parameter Real gamma_max(unit="m") = 7e-6 "Geometric TE amplitude at f_dte = 1 (precision class)";

  // ---- derived parameters ----
  parameter Real N_ap(unit="1") = GearDiag.Functions.lcm(Np, Ng)/Np "Number of assembly phases, lcm(Np, Ng)/Np";
  parameter Real f_mesh(unit="Hz") = Np*f_pinion "Mesh frequency";
  parameter Real f_fe(unit="Hz") = f_mesh/N_ap "Geometric TE (assembly-phase) frequency";
  parameter Real x_static(unit="m") = T/r_p/(K*(1 + a_f*GearDiag.Functions.formWave(0, f_f)
    - d_f*GearDiag.Functions.toothWindow(0, Np, 0, eps_c, q_c, r_c)))
    "Static deflection at t = 0 (faulty tooth in mesh, zero TE): the start point";

  // ---- hooks of the law (neutral here) ----
  Real k_mod = 0 "Extra relative stiffness modulation (effects)";
  Real e_extra(unit="m") = 0 "Extra transmission error (effects)";
  Real t_angle(unit="s") = time "Pinion angle over its mean speed: the time a steady shaft has turned for (effects: a speed fluctuation)";

  Real toothIndex "Index of the pinion tooth in mesh, 0 is the faulty one";
  Real a "Stiffness variation amplitude of the tooth in mesh";
  Real sigma "Normalised stiffness wave";
  Real e_ate(unit="m") "Assembly transmission error";
  Real e_dte(unit="m") "Geometric transmission error";
  output Real stiffness(unit="N/m") "Mesh stiffness";
equation
  // Tooth periods start a quarter mesh cycle early, where sigma = 0, so the jump of a
  // between teeth leaves k continuous and the solver sees no discontinuity.
  toothIndex = mod(floor(f_mesh*t_angle + 0.25), Np);
  a = if toothIndex < 0.5 then a_f else a0;
  sigma = GearDiag.Functions.formWave(2*GearDiag.pi*f_mesh*t_angle, f_f);
  stiffness = K*(1 + a*sigma + k2*cos(4*GearDiag.pi*f_mesh*t_angle + phi2)
    + k4*cos(8*GearDiag.pi*f_mesh*t_angle + phi4)
    - d_f*GearDiag.Functions.toothWindow(f_mesh*t_angle, Np, 0, eps_c, q_c, r_c) + k_mod);
  e_ate = f_ate*xi_max*sin(2*GearDiag.pi*f_pinion*t_angle);
  e_dte = f_dte*gamma_max*sin(2*GearDiag.pi*f_fe*t_angle);
  annotation(Documentation(info="<html>
<p>The law of a gear mesh: its parameters, stiffness and transmission errors, on the pinion's angle.</p>
<pre>
k(t) = K*(1 + a(tooth)*sigma(theta_mesh, f_f) + k2*cos(2*theta_mesh + phi2)
           + k4*cos(4*theta_mesh + phi4) - d_f*w0(theta_mesh) + k_mod)   Eq. (3) and beyond
e_ate = f_ate*xi_max*sin(w_pinion*t)                         assembly TE, Eq. (4)
e_dte = f_dte*gamma_max*sin(w_fe*t)                          geometric TE, Eq. (5), w_fe = w_mesh/N_ap
The kinematics run on t_angle, the pinion angle over its mean speed (= time).
GearPair (the paper's SDOF pair) and Components.GearMesh (a stage between two shafts)
extend it; k_mod, e_extra and t_angle are hooks with neutral declaration equations.
---- fault parameters (normalised, estimated by pydiag) ----
</pre>
</html>"));
end PartialMeshLaw;
