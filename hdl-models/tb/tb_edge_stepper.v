// Self-checking testbench of edge_stepper: fields per vector: load, q_in, r_in, a, b, d,
// expected q, expected r, expected carry (q, a in Q_BITS two's complement).
`timescale 1ns/1ps
`include "params.vh"
module tb_edge_stepper;
    reg clk = 0;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [63:0] eq, er, ec;
    reg load;
    reg [`P_Q_BITS-1:0] q_in, a;
    reg [`P_D_BITS-1:0] r_in, b, d;
    wire [`P_Q_BITS-1:0] q;
    wire [`P_D_BITS-1:0] r;
    wire carry;
    integer k, errors, first;
    edge_stepper #(.Q_BITS(`P_Q_BITS), .D_BITS(`P_D_BITS))
        dut (.clk(clk), .load(load), .q_in(q_in), .r_in(r_in), .a(a), .b(b), .d(d),
             .q(q), .r(r), .carry(carry));
    initial begin
        $readmemh("vectors.hex", mem);
        errors = 0;
        first = -1;
        for (k = 0; k < `N_VECTORS; k = k + 1) begin
            load = mem[k*`N_FIELDS];
            q_in = mem[k*`N_FIELDS+1];
            r_in = mem[k*`N_FIELDS+2];
            a = mem[k*`N_FIELDS+3];
            b = mem[k*`N_FIELDS+4];
            d = mem[k*`N_FIELDS+5];
            #1 clk = 1;
            #1 clk = 0;
            eq = mem[k*`N_FIELDS+6];
            er = mem[k*`N_FIELDS+7];
            ec = mem[k*`N_FIELDS+8];
            if (q !== eq[`P_Q_BITS-1:0] || eq >> `P_Q_BITS != 0 || r !== er[`P_D_BITS-1:0]
                || er >> `P_D_BITS != 0 || carry !== ec[0] || ec > 1) begin
                if (errors == 0) first = k;
                errors = errors + 1;
            end
        end
        if (errors == 0) $display("TESTBENCH OK %0d vectors", `N_VECTORS);
        else $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (load=%0h expected q=%0h r=%0h carry=%0h)",
                      errors, `N_VECTORS, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+6],
                      mem[first*`N_FIELDS+7], mem[first*`N_FIELDS+8]);
        $finish;
    end
endmodule
