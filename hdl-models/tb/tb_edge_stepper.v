// Self-checking testbench of edge_stepper: fields per vector: load, q_in, r_in, a, b, d,
// expected q, expected r, expected carry (q, a in Q_BITS two's complement). The vectors
// stream through the handshake (hs_tb.vh); the first is a load.
`timescale 1ns/1ps
`include "params.vh"
module tb_edge_stepper;
    `include "hs_tb.vh"
    reg [63:0] eq, er, ec;
    reg load;
    reg [`P_Q_BITS-1:0] q_in, a;
    reg [`P_D_BITS-1:0] r_in, b, d;
    wire [`P_Q_BITS-1:0] q;
    wire [`P_D_BITS-1:0] r;
    wire carry;
    edge_stepper #(.Q_BITS(`P_Q_BITS), .D_BITS(`P_D_BITS))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
             .out_valid(out_valid), .out_ready(out_ready), .load(load), .q_in(q_in),
             .r_in(r_in), .a(a), .b(b), .d(d), .q(q), .r(r), .carry(carry));
    task drive(input integer k);
        begin
            load = mem[k*`N_FIELDS];
            q_in = mem[k*`N_FIELDS+1];
            r_in = mem[k*`N_FIELDS+2];
            a = mem[k*`N_FIELDS+3];
            b = mem[k*`N_FIELDS+4];
            d = mem[k*`N_FIELDS+5];
        end
    endtask
    task check(input integer k, output reg bad_k);
        begin
            eq = mem[k*`N_FIELDS+6];
            er = mem[k*`N_FIELDS+7];
            ec = mem[k*`N_FIELDS+8];
            bad_k = q !== eq[`P_Q_BITS-1:0] || eq >> `P_Q_BITS != 0 || r !== er[`P_D_BITS-1:0]
                || er >> `P_D_BITS != 0 || carry !== ec[0] || ec > 1;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (load=%0h expected q=%0h r=%0h carry=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+6],
                 mem[first*`N_FIELDS+7], mem[first*`N_FIELDS+8]);
    endtask
endmodule
