import numpy as np, warnings
warnings.simplefilter("error")
from scatterlab.pbrdf import Model, HyperCauchy, PEC
from scatterlab import polarization
th = np.r_[0, np.radians([30, 60, 85, 89.99]), np.pi/2]
TI, TR, PH = np.meshgrid(th, th, np.r_[0, 0.5, np.pi/2, np.pi], indexing="ij")
for b, nu in [(1e-4, 2.0), (1e-4, 1.05), (1e4, 2.0), (1e4, 1.05), (0.3, 1.05), (0.3, 50.0), (1.0, 1e6)]:
  for sh in ["torrance-sparrow", "smith", "none"]:
    for df in ["hyde", "reciprocal"]:
      try:
        m = Model(distribution=HyperCauchy(b, nu), shadowing=sh, diffuse=df)
        for e in [1.5-1e3j, 1e-8, PEC]:
            F = m.mueller(e, TI, TR, PH); d = m.dolp(e, TI, TR, PH)
            bad = ~np.isfinite(F).all((-1,-2)); neg = F[...,0,0] < 0
            rho = m.dhr_pec(th)
            msg=[]
            if bad.any(): msg.append(f"nonfinite {bad.sum()}")
            if neg.any(): msg.append("neg M00")
            if np.any(rho<0) or (sh!="none" and np.any(rho>1+1e-9)) or not np.all(np.isfinite(rho)): msg.append(f"rho {rho}")
            if msg: print(b, nu, sh, df, e, msg)
      except Exception as ex:
        print(b, nu, sh, df, "EXC", type(ex).__name__, str(ex)[:200])
print("done")
