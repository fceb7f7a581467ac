//! Option layers: structs whose every field may be unset, laid one over another field by field.
//!
//! Why: the fit options come from two places, the TOML spec file and the command-line flags, and
//! flags override the file. Each concern's options are one struct deriving both `clap::Args` (with
//! the crate's `cli` feature: a library of training linked without a command-line parser does
//! not carry clap) and `serde::Deserialize` (see [`crate::spec`]), with every field an `Option` (or
//! a list, which adds up); [`layer!`](crate::layer!) writes the struct and its [`Layer`]
//! implementation from the one field list (attributes, `cfg_attr` ones included, pass through), so
//! the merge and the set of known spec keys never need a second list of names.
//! (The alternative, clap's defaults resolved after reading the TOML, would need clap to tell a
//! default from a value given; with unset fields the defaults live in one place,
//! [`crate::FitOptions::new`].)

/// A field of a layer: how a value given later (a flag) lies over one given earlier (the file).
pub trait Field {
    /// `other` over `self`.
    fn overlay_field(&mut self, other: Self);
    /// The spec keys of a field named `name`: its own name in kebab-case, or, for a layer
    /// flattened into another (a method's own options), the keys of its fields.
    fn field_keys(name: &str, out: &mut Vec<String>) {
        out.push(name.replace('_', "-"));
    }
}

impl<T> Field for Option<T> {
    /// A value given later wins.
    fn overlay_field(&mut self, other: Self) {
        if other.is_some() {
            *self = other;
        }
    }
}

impl<T> Field for Vec<T> {
    /// Lists add up (features and signals of the file, then those of the flags).
    fn overlay_field(&mut self, other: Self) {
        self.extend(other);
    }
}

/// A struct of [`Field`]s.
pub trait Layer {
    /// `other` over `self`, field by field.
    fn overlay(&mut self, other: Self);
    /// The spec keys of the fields (kebab-case).
    fn keys(out: &mut Vec<String>);
}

/// Defines a layer struct (attributes and doc comments pass through to the struct and its
/// fields) and its [`Layer`] implementation from the same field list. The struct is also a
/// [`Field`] whose keys are its fields' keys, so a layer can be flattened into another (with
/// `#[serde(flatten)]` and clap's `#[command(flatten)]`): each method's own options are laid into
/// the method options this way ([`crate::registry`]).
#[macro_export]
macro_rules! layer {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty, )*
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        impl $crate::layer::Layer for $name {
            #[allow(unused_variables)]
            fn overlay(&mut self, other: Self) {
                $( $crate::layer::Field::overlay_field(&mut self.$field, other.$field); )*
            }

            #[allow(unused_variables)]
            fn keys(out: &mut Vec<String>) {
                $( <$ty as $crate::layer::Field>::field_keys(stringify!($field), out); )*
            }
        }

        impl $crate::layer::Field for $name {
            fn overlay_field(&mut self, other: Self) {
                $crate::layer::Layer::overlay(self, other);
            }

            fn field_keys(_name: &str, out: &mut Vec<String>) {
                <$name as $crate::layer::Layer>::keys(out);
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    crate::layer! {
        #[derive(Default)]
        pub struct Demo {
            pub some_value: Option<f64>,
            pub item: Vec<String>,
        }
    }

    #[test]
    fn later_values_win_lists_add_up_and_keys_are_kebab_case() {
        let mut a = Demo {
            some_value: Some(1.0),
            item: vec!["a".into()],
        };
        a.overlay(Demo {
            some_value: None,
            item: vec!["b".into()],
        });
        assert_eq!(a.some_value, Some(1.0));
        a.overlay(Demo {
            some_value: Some(2.0),
            item: Vec::new(),
        });
        assert_eq!(a.some_value, Some(2.0));
        assert_eq!(a.item, ["a", "b"]);
        let mut keys = Vec::new();
        Demo::keys(&mut keys);
        assert_eq!(keys, ["some-value", "item"]);
    }
}
