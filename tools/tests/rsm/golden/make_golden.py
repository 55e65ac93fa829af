"""Golden values for tilth's response-surface tests, from an independent code (statsmodels).

Fits, with statsmodels' OLS and its Type III ANOVA, the two tables the tests use:
- table 6 of the reference study (Plackett-Burman, 15 runs): linear model of the repose angle
  in x1..x7 plus an indicator of the three centre points (the curvature term);
- table 9 (Box-Behnken, the 14 printed runs): a full quadratic in x4, x6, x7 of each
  moisture's relative error.
Writes golden.json beside this file. Run: python make_golden.py (numpy, pandas, statsmodels).
"""

import json
import pathlib

import pandas as pd
import statsmodels
import statsmodels.formula.api as smf
from statsmodels.stats.anova import anova_lm

here = pathlib.Path(__file__).resolve().parent
data = here.parents[3] / "sweeps" / "li2022" / "data"


def summary(model, terms):
    table = anova_lm(model, typ=3)
    infl = model.get_influence()
    press = float(((model.resid / (1.0 - infl.hat_matrix_diag)) ** 2).sum())
    sst = float(((model.model.endog - model.model.endog.mean()) ** 2).sum())
    out = {
        "coefficients": {k: float(model.params[k]) for k in ["Intercept"] + terms},
        "sum_sq": {k: float(table.loc[k, "sum_sq"]) for k in terms},
        "p": {k: float(table.loc[k, "PR(>F)"]) for k in terms},
        "residual_sum_sq": float(model.ssr),
        "residual_df": int(model.df_resid),
        "r2": float(model.rsquared),
        "adj_r2": float(model.rsquared_adj),
        "pred_r2": 1.0 - press / sst,
    }
    return out


golden = {"generator": f"statsmodels {statsmodels.__version__}"}

pb = pd.read_csv(data / "table06_pb_runs.csv")
pb["curvature"] = (pb[[f"x{i}" for i in range(1, 8)]] == 0).all(axis=1).astype(float)
terms = [f"x{i}" for i in range(1, 8)] + ["curvature"]
golden["table06"] = summary(smf.ols("repose_angle_deg ~ " + " + ".join(terms), pb).fit(), terms)

bbd = pd.read_csv(data / "table09_bbd_runs.csv").rename(
    columns={"x4_coded": "x4", "x6_coded": "x6", "x7_coded": "x7"}
)
names = {
    "x4": "x4", "x6": "x6", "x7": "x7",
    "x4:x6": "x4*x6", "x4:x7": "x4*x7", "x6:x7": "x6*x7",
    "I(x4 ** 2)": "x4^2", "I(x6 ** 2)": "x6^2", "I(x7 ** 2)": "x7^2",
}
formula = " ~ x4 + x6 + x7 + x4:x6 + x4:x7 + x6:x7 + I(x4**2) + I(x6**2) + I(x7**2)"
for m in (3, 6, 9, 12):
    fit = smf.ols(f"err_{m}pct" + formula, bbd).fit()
    s = summary(fit, list(names))
    for key in ("coefficients", "sum_sq", "p"):
        s[key] = {names.get(k, k): v for k, v in s[key].items()}
    golden[f"table09_err_{m}pct"] = s

(here / "golden.json").write_text(json.dumps(golden, indent=1) + "\n")
print("wrote", here / "golden.json")
