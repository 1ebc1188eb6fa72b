within GearDiag.Components;
model HousingMode "One housing mode between the mesh force and a housing accelerometer"
  // A mode of modal mass m_h, natural frequency f_n and damping ratio zeta, driven by the
  // force the mesh passes into the housing:
  //   m_h*(z'' + 2*zeta*w_n*z' + w_n^2*z) = F,   a = z''   (w_n = 2*pi*f_n)
  // The accelerance a/F is 1/m_h far above f_n, rises to 1/(2*zeta*m_h) at f_n and falls
  // as (f/f_n)^2 below: lines near f_n are amplified, low orders attenuated.
  parameter Real f_n(unit="Hz", min=1) = 2500 "Natural frequency of the housing mode";
  parameter Real zeta(unit="1", min=1e-4, max=1) = 0.05 "Damping ratio of the housing mode";
  parameter Real m_h(unit="kg", min=1e-6) = 0.5 "Modal mass of the housing mode";
  parameter Real F_0(unit="N") = 0 "Force at the start (the mode starts at rest under it)";
  input Real F(unit="N") "Force from the mesh into the housing";
  Real z(unit="m", start=F_0/(m_h*(2*GearDiag.pi*f_n)^2), fixed=true, nominal=1e-8) "Modal displacement";
  Real w(unit="m/s", start=0, fixed=true, nominal=1e-5) "Modal velocity";
  output Real a(unit="m/s2") "Housing acceleration at the sensor";
equation
  der(z) = w;
  a = F/m_h - 2*zeta*(2*GearDiag.pi*f_n)*w - (2*GearDiag.pi*f_n)^2*z;
  der(w) = a;
  annotation(Documentation(info="<html>
<p>One housing mode between the mesh force and a housing accelerometer.</p>
<pre>
A mode of modal mass m_h, natural frequency f_n and damping ratio zeta, driven by the
force the mesh passes into the housing:
  m_h*(z'' + 2*zeta*w_n*z' + w_n^2*z) = F,   a = z''   (w_n = 2*pi*f_n)
The accelerance a/F is 1/m_h far above f_n, rises to 1/(2*zeta*m_h) at f_n and falls
as (f/f_n)^2 below: lines near f_n are amplified, low orders attenuated.
</pre>
</html>"));
end HousingMode;
