//! `tilth laws`: every registered contact law, for writing `[contact]` and `[[pairs]]`.

use anyhow::Result;
use std::io::Write;
use tilth_kernel::contact::Slot;
use tilth_kernel::contact::laws::REGISTRY;

/// The slots in pipeline order, with what a scene may put there.
const SLOTS: [(Slot, &str); 6] = [
    (Slot::Normal, "required, one law"),
    (Slot::Damping, "optional, one law"),
    (Slot::Tangential, "optional, one law"),
    (Slot::Rolling, "optional, one law"),
    (Slot::Extra, "optional, a list of laws"),
    (Slot::Bond, "optional, one law; named in [contact] extra"),
];

pub fn laws(out: &mut dyn Write) -> Result<()> {
    writeln!(
        out,
        "Contact laws. [contact] names the law of each slot (e.g. normal = \"jkr\");\n\
         each [[pairs]] entry gives the parameters of all chosen laws for one material pair.\n\
         A cohesive law needs tangential and rolling laws that allow cohesion.\n\
         Parameter lines read: key, unit, allowed range, default, meaning."
    )?;
    for (slot, what) in SLOTS {
        writeln!(out, "\n[contact] {} ({what})", slot.name())?;
        for law in REGISTRY.iter().filter(|l| l.slot == slot) {
            writeln!(out, "  {:<16} {}", law.name, law.summary)?;
            writeln!(
                out,
                "  {:<16} cohesive: {}; allows cohesion: {}",
                "",
                yes_no(law.cohesive),
                yes_no(law.allows_cohesion)
            )?;
            if law.params.is_empty() {
                writeln!(out, "  {:<16} parameters: none", "")?;
            }
            for p in law.params {
                let default = match p.default {
                    Some(d) => format!("default {d}"),
                    None => "required".into(),
                };
                writeln!(
                    out,
                    "  {:<16} {:<16} {:<8} {:<12} {:<14} {}",
                    "",
                    p.key,
                    p.unit,
                    p.range_text(),
                    default,
                    p.doc
                )?;
            }
            if !law.history.is_empty() {
                writeln!(out, "  {:<16} history: {}", "", law.history.join(", "))?;
            }
        }
    }
    Ok(())
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}
