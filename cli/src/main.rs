fn main(){ println!("{}", cadr_core::probe()); }
