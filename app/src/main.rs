//! The `vigie` binary: command-line entry point.

fn main() {
    println!("vigie: work in progress");
}
