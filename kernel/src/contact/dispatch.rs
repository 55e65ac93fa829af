//! One enum per slot over the registered laws, so the pipeline calls a law without `dyn`.
//!
//! Through a `Box<dyn NormalLaw>` every call is an indirect jump the compiler cannot look
//! into: the law's 24- and 48-byte results come back through memory and are read back
//! before those stores have finished, and nothing is inlined. A `match` on a small enum is
//! a branch the CPU predicts perfectly (one model uses one law per slot), each arm inlines,
//! and the law's coefficients sit in the pair's laws instead of behind a pointer. On the
//! settling-bed benchmark this took about a tenth off the pair phase (BENCHMARKS.md).
//!
//! The registry (`laws/mod.rs`) lists each law once; [`law_enum!`] turns a slot's list
//! into `AnySlot`, with `From` for each law and the slot's trait implemented by forwarding
//! every method to the law inside. A forwarded list must name *every* method of the trait,
//! default ones included, or the enum would run the default instead of a law's override:
//! the lists sit in `laws/mod.rs`, and each trait's doc points there.

/// A law type inside its slot's enum: `Some` when `any` holds this law.
pub trait OfAny<A> {
    fn of_any(any: &A) -> Option<&Self>;
}

/// `law_enum!(AnyNormal: NormalLaw [Hertz(hertz::Hertz) ...] { fn force(&self, ...) -> T; ... })`
macro_rules! law_enum {
    ($(#[$doc:meta])* $enum:ident: $trait:ident $variants:tt {
        $(fn $m:ident(&self $(, $a:ident: $t:ty)*) -> $r:ty;)*
    }) => {
        law_enum!(@enum $(#[$doc])* $enum $variants);
        impl $trait for $enum {
            $(
                #[inline(always)]
                fn $m(&self $(, $a: $t)*) -> $r {
                    law_enum!(@match self, $enum $variants, $m($($a),*))
                }
            )*
        }
    };
    (@enum $(#[$doc:meta])* $enum:ident [$($var:ident($ty:path))*]) => {
        $(#[$doc])*
        pub enum $enum {
            $($var($ty),)*
        }
        $(
            impl From<$ty> for $enum {
                fn from(law: $ty) -> Self {
                    $enum::$var(law)
                }
            }
            impl $crate::contact::dispatch::OfAny<$enum> for $ty {
                #[allow(unreachable_patterns)]
                fn of_any(any: &$enum) -> Option<&Self> {
                    match any {
                        $enum::$var(law) => Some(law),
                        _ => None,
                    }
                }
            }
        )*
    };
    (@match $s:ident, $enum:ident [$($var:ident($ty:path))*], $m:ident $args:tt) => {
        match $s {
            $($enum::$var(law) => law.$m $args,)*
        }
    };
}
