within GearDiag;
model GearPair "Translational SDOF gear mesh: periodic stiffness, one faulty pinion tooth, assembly and geometric transmission errors"
  // Paper Eq. (6), written as a balance of forces along the line of action:
  //   m*x'' + c*x' + k_eff(t)*(x - e(t)) = T/r_p + F_extra
  //   k(t)  = K*(1 + a(tooth)*sigma(theta_mesh, f_f) + k2*cos(2*theta_mesh + phi2)
  //                      + k4*cos(4*theta_mesh + phi4) - d_f*w0(theta_mesh) + k_mod)
  //   e(t)  = e_ate + e_dte + e_extra
  //   e_ate = f_ate*xi_max*sin(w_pinion*t)          assembly TE, Eq. (4)
  //   e_dte = f_dte*gamma_max*sin(w_fe*t)            geometric TE, Eq. (5), w_fe = w_mesh/N_ap
  // The kinematics run on t_angle, the pinion angle over its mean speed (= time).
  // The law (parameters, k, e, t_angle) is Interfaces.PartialMeshLaw, shared with
  // Components.GearMesh. k_mod, e_extra, F_extra, contact, acc_sensor and t_angle are hooks
  // with neutral declaration equations; a model in Effects/ overrides one of them with a
  // modifier on `extends GearPair(...)`.

  extends GearDiag.Interfaces.PartialMeshLaw;
  parameter Real m(unit="kg") = 0.5 "Equivalent mass of the gear pair along the line of action";

  // ---- effect hooks (neutral here) ----
  Real F_extra(unit="N") = 0 "Extra force on the line of action (effects)";
  Real contact = 1 "Contact factor, 1 while the teeth touch (effects)";
  Real acc_sensor(unit="m/s2") = der(v) "What the acc sensor sees: the mesh acceleration (effects: a transfer path)";

  // ---- states and internal variables ----
  // Nominals set the solvers' absolute tolerance (fmpy's CVode: atol = rtol*nominal).
  Real x(unit="m", start=x_static, fixed=true, nominal=1e-5) "Mesh displacement along the line of action";
  Real v(unit="m/s", start=0, fixed=true, nominal=1e-3) "Mesh velocity";

  // ---- outputs ----
  output Real acc(unit="m/s2") "Sensor acceleration along the line of action (the diagnosed signal)";
  output Real disp(unit="m") "Mesh displacement";
  output Real mesh_force(unit="N") "Dynamic mesh force";
equation
  mesh_force = contact*stiffness*(x - e_ate - e_dte - e_extra) + c*v;
  der(x) = v;
  m*der(v) + mesh_force = T/r_p + F_extra;
  acc = acc_sensor;
  disp = x;
  annotation(Documentation(info="<html>
<p>Translational SDOF gear mesh: periodic stiffness, one faulty pinion tooth, assembly and geometric transmission errors.</p>
<pre>
Paper Eq. (6), written as a balance of forces along the line of action:
  m*x'' + c*x' + k_eff(t)*(x - e(t)) = T/r_p + F_extra
  k(t)  = K*(1 + a(tooth)*sigma(theta_mesh, f_f) + k2*cos(2*theta_mesh + phi2)
                     + k4*cos(4*theta_mesh + phi4) - d_f*w0(theta_mesh) + k_mod)
  e(t)  = e_ate + e_dte + e_extra
  e_ate = f_ate*xi_max*sin(w_pinion*t)          assembly TE, Eq. (4)
  e_dte = f_dte*gamma_max*sin(w_fe*t)            geometric TE, Eq. (5), w_fe = w_mesh/N_ap
The kinematics run on t_angle, the pinion angle over its mean speed (= time).
The law (parameters, k, e, t_angle) is Interfaces.PartialMeshLaw, shared with
Components.GearMesh. k_mod, e_extra, F_extra, contact, acc_sensor and t_angle are hooks
with neutral declaration equations; a model in Effects/ overrides one of them with a
modifier on `extends GearPair(...)`.
</pre>
</html>"));
end GearPair;
