"""Controller: MuJoCo plant built from DH parameters, QP differential IK, self-motion."""
