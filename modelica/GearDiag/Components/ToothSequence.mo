within GearDiag.Components;
model ToothSequence "Something that repeats every turn of a gear, tooth by tooth: its Fourier series in the gear's angle"
  // Pitch, profile and runout errors of the teeth of a gear repeat every turn of it: each
  // tooth a little early or late, high or low. Of Z teeth that is Z values a turn, whose
  // orders 1..Z/2 say all of it (an order k above Z/2 makes the lines of order Z - k
  // round the next mesh harmonic). As a series in the gear's angle w:
  //   e = sum_k c[k]*cos(k*w) + s[k]*sin(k*w),   k = 1..n
  // in the unit of its coefficients: a transmission error in m, a tooth's lead or lag in
  // tooth pitches. A gear of Z teeth leaves the orders above Z/2 at 0.
  parameter Integer n = 48 "Orders of the series: a gear of up to 2n teeth";
  parameter Real f_shaft(unit="Hz") = 25 "Shaft speed";
  parameter Real c[n] = zeros(n) "Cosine coefficients of the orders 1..n";
  parameter Real s[n] = zeros(n) "Sine coefficients of the orders 1..n";
  input Real t_angle(unit="s") "Shaft angle over its mean speed";
  output Real e "The sequence at the gear's angle";
protected
  Real w(unit="rad") = 2*GearDiag.pi*f_shaft*t_angle "Gear angle";
equation
  e = sum(c[k]*cos(k*w) + s[k]*sin(k*w) for k in 1:n);
  annotation(Documentation(info="<html>
<p>Something that repeats every turn of a gear, tooth by tooth (the pitch, profile or
runout errors of its teeth, of any shape), as a Fourier series in the gear's angle, in the
unit of its coefficients. Of a gear of Z teeth the orders 1..Z/2 say all of a
tooth-by-tooth sequence; the rest stay 0.</p>
</html>"));
end ToothSequence;
