within GearDiag;
package Functions "Pure functions used by the gear models"
  annotation(Documentation(info="<html>
<p>Pure functions used by the gear models.</p>
</html>"));
end Functions;
