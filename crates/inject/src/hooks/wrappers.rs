//! What the program calls instead of the watched GL functions: each
//! wrapper calls the handler of its name in [`crate::state::handlers`]
//! with the real function first.

use crate::real::{Slot, next_definition};
use crate::real::{real, real_type, watched_functions};

/// Declares the wrappers of the watched functions, and the lookup of a
/// wrapper by name.
macro_rules! declare_wrappers {
    ($( $name:ident ( $($arg:ident : $ty:ty),* ) $(-> $ret:ty)? ; )*) => {
        /// What the program calls instead: handed out by the get-proc-addresses
        /// and `dlsym`, and exported under the function's own name for a
        /// program linked with libGL or libEGL (the preload comes first).
        #[allow(non_snake_case)]
        mod wrapper {
            use super::{next_definition, real, real_type};
            use std::ffi::{c_char, c_ulong, c_void};
            $(
                /// The watched function: the handler around the real one.
                ///
                /// # Safety
                ///
                /// The GL function's own contract.
                #[unsafe(no_mangle)]
                #[allow(clippy::too_many_arguments)]
                pub unsafe extern "system" fn $name($($arg: $ty),*) $(-> $ret)? {
                    // Handed out: the slot was filled first. Called by its
                    // exported name: the next definition (libGL's, libEGL's).
                    if real::$name.get().is_none() {
                        real::$name.set(next_definition(concat!(stringify!($name), "\0")));
                    }
                    let Some(address) = real::$name.get() else {
                        return Default::default();
                    };
                    // SAFETY: the driver's address for this function.
                    let real = unsafe { std::mem::transmute::<usize, real_type::$name>(address) };
                    crate::state::handlers::$name(real, $($arg),*)
                }
            )*
        }

        /// The slot and the wrapper of the watched function `name`.
        pub(super) fn wrapper_for(name: &[u8]) -> Option<(&'static Slot, usize)> {
            $(
                if name == stringify!($name).as_bytes() {
                    return Some((&real::$name, wrapper::$name as *const () as usize));
                }
            )*
            None
        }
    };
}

watched_functions!(declare_wrappers);
