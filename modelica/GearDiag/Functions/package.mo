within GearDiag;
package Functions "Pure functions used by the gear models"
end Functions;
