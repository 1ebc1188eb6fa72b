within GearDiag.Functions;
function lcm "Least common multiple of two positive integers"
  input Integer a;
  input Integer b;
  output Integer l;
algorithm
  l := div(a*b, GearDiag.Functions.gcd(a, b));
  annotation(Documentation(info="<html>
<p>Least common multiple of two positive integers.</p>
</html>"));
end lcm;
